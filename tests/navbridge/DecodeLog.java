// Decodes every event of an LCM log the way lcm-spy does: the first 8 bytes of a message
// are its type fingerprint, looked up among the qnav classes of qnav_lcmtypes.jar. Prints
// one line per event and exits 1 if any event has no class or fails to decode, or if a
// few known values (written by make_sample_log) come back wrong.
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.EOFException;
import java.util.HashMap;
import java.util.Map;

import lcm.logging.Log;

public class DecodeLog {
    public static void main(String[] args) throws Exception {
        Class<?>[] types = {qnav.scan_t.class, qnav.goal_t.class, qnav.command_t.class,
                            qnav.path_qualities_t.class, qnav.pose_t.class,
                            qnav.link_status_t.class};
        Map<Long, Class<?>> byFingerprint = new HashMap<>();
        for (Class<?> t : types) {
            byFingerprint.put(t.getField("LCM_FINGERPRINT").getLong(null), t);
        }
        Log log = new Log(args[0], "r");
        int decoded = 0, failed = 0;
        while (true) {
            Log.Event ev;
            try {
                ev = log.readNext();
            } catch (EOFException e) {
                break;
            }
            long fp = new DataInputStream(new ByteArrayInputStream(ev.data)).readLong();
            Class<?> t = byFingerprint.get(fp);
            if (t == null) {
                System.out.println(ev.channel + ": no qnav type has fingerprint " + fp);
                failed++;
                continue;
            }
            Object msg = t.getConstructor(byte[].class).newInstance((Object) ev.data);
            System.out.println(ev.channel + ": decoded as " + t.getName());
            decoded++;
            if (msg instanceof qnav.scan_t && ((qnav.scan_t) msg).ranges_mm[15] != 1015) failed++;
            if (msg instanceof qnav.command_t && ((qnav.command_t) msg).heading_deg != -30) failed++;
            if (msg instanceof qnav.path_qualities_t
                && ((qnav.path_qualities_t) msg).quality_q15[359] != 359 * 90) failed++;
            if (msg instanceof qnav.pose_t && ((qnav.pose_t) msg).y_m != 2.5) failed++;
        }
        System.out.println(decoded + " decoded, " + failed + " failed");
        System.exit(failed == 0 && decoded > 0 ? 0 : 1);
    }
}
