/*
 * qnav-spy --check: lcm-spy itself (lcm.spy.Spy, its window and its decoding) run for a
 * while, then what it received printed, one line per channel: NAME TYPE COUNT (TYPE is the
 * class lcm-spy decoded it with, "-" when it could not), and optionally its window saved as
 * a PNG. Exit 0 when at least one channel decoded, 1 otherwise. In package lcm.spy to read
 * Spy's channel list, which lcm-spy keeps package-private.
 */
package lcm.spy;

import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Robot;
import java.awt.image.BufferedImage;
import java.io.File;
import java.util.ArrayList;
import javax.imageio.ImageIO;
import javax.swing.SwingUtilities;

public class QnavSpyCheck {
    public static void main(String[] args) throws Exception {
        if (args.length < 2) {
            System.err.println("usage: QnavSpyCheck URL SECONDS [SCREENSHOT.png]");
            System.exit(2);
        }
        String url = args[0].isEmpty() ? null : args[0];
        double seconds = Double.parseDouble(args[1]);
        Spy spy = new Spy(url);
        Thread.sleep((long) (seconds * 1000.0));
        final ArrayList<ChannelData> seen = new ArrayList<ChannelData>();
        SwingUtilities.invokeAndWait(new Runnable() {
            public void run() {
                synchronized (spy) {
                    seen.addAll(spy.channelList);
                }
            }
        });
        int decoded = 0;
        for (ChannelData cd : seen) {
            String type = cd.cls == null ? "-" : cd.cls.getName();
            decoded += cd.cls == null ? 0 : 1;
            System.out.println(cd.name + " " + type + " " + cd.nreceived);
        }
        if (args.length >= 3) {
            for (Frame f : Frame.getFrames()) {
                if (f.isShowing()) {
                    Rectangle r = f.getBounds();
                    BufferedImage img = new Robot().createScreenCapture(r);
                    ImageIO.write(img, "png", new File(args[2]));
                    break;
                }
            }
        }
        System.out.flush();
        System.exit(decoded > 0 ? 0 : 1);
    }
}
