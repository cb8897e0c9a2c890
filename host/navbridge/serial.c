/*
 * Serial port setup for navbridge (serial.h): termios raw mode, 8N1, no flow control.
 * Works the same on a USB serial adapter and on a pseudo-terminal (SIL and tests).
 */
#define _DEFAULT_SOURCE
#include "serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

static speed_t baud_constant(long baud)
{
    switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 1000000: return B1000000;
    default: return (speed_t)0;
    }
}

int qnav_serial_baud_ok(long baud)
{
    return baud_constant(baud) != (speed_t)0;
}

int qnav_serial_open(const char *device, long baud, char *err, size_t errlen)
{
    struct termios tio;
    speed_t sp = baud_constant(baud);
    int fd;

    if (sp == (speed_t)0) {
        snprintf(err, errlen, "--baud %ld: unsupported rate (" QNAV_SERIAL_RATES ")", baud);
        return -1;
    }
    fd = open(device, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(err, errlen, "%s: %s", device, strerror(errno));
        return -1;
    }
    if (tcgetattr(fd, &tio) != 0) {
        snprintf(err, errlen, "%s: not a serial port (%s)", device, strerror(errno));
        close(fd);
        return -1;
    }
    cfmakeraw(&tio);
    tio.c_cflag |= (tcflag_t)(CLOCAL | CREAD);
    tio.c_cflag &= (tcflag_t)~(CSTOPB | CRTSCTS | PARENB);
    tio.c_iflag &= (tcflag_t)~(IXON | IXOFF | IXANY);
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    if (cfsetispeed(&tio, sp) != 0 || cfsetospeed(&tio, sp) != 0 ||
        tcsetattr(fd, TCSANOW, &tio) != 0) {
        snprintf(err, errlen, "%s: cannot set %ld baud raw mode (%s)", device, baud,
                 strerror(errno));
        close(fd);
        return -1;
    }
    tcflush(fd, TCIOFLUSH);
    return fd;
}

int qnav_serial_write_all(int fd, const unsigned char *bytes, size_t n)
{
    size_t done = 0;
    while (done < n) {
        ssize_t w = write(fd, bytes + done, n - done);
        if (w > 0) {
            done += (size_t)w;
        } else if (w < 0 && (errno == EAGAIN || errno == EINTR)) {
            struct pollfd p = {fd, POLLOUT, 0};
            if (poll(&p, 1, 200) <= 0) {
                return -1; /* port stuck: drop the frame rather than hang the loop */
            }
        } else {
            return -1;
        }
    }
    return 0;
}
