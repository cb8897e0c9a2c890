/*
 * Opening a serial port for the link: raw 8N1, no flow control, non-blocking, at one of
 * the standard baud rates. Errors come back as one line naming the device or the rate.
 */
#ifndef QNAV_NAVBRIDGE_SERIAL_H
#define QNAV_NAVBRIDGE_SERIAL_H

#include <stddef.h>

/* The rates qnav_serial_baud_ok() accepts, for messages. */
#define QNAV_SERIAL_RATES "9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 1000000"

/* 1 if baud is a rate the bridge supports (termios has a constant for it). */
int qnav_serial_baud_ok(long baud);

/* Open device raw at baud. Returns a file descriptor, or -1 with a message in err. */
int qnav_serial_open(const char *device, long baud, char *err, size_t errlen);

/* Write all n bytes (waiting for the port when it is full); 0 or -1. */
int qnav_serial_write_all(int fd, const unsigned char *bytes, size_t n);

#endif /* QNAV_NAVBRIDGE_SERIAL_H */
