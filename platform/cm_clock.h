/*
 * cm_clock.h - the one monotonic clock of the link protocol, the transports
 * and the workstation's timings: CLOCK_MONOTONIC, which never steps with the
 * wall clock, so deadlines survive an NTP or RTC adjustment on the board.
 *
 * Header-only (static inline): every program that links a transport, the
 * link or model_load.c gets it without another object on its link line.
 * The including file defines _POSIX_C_SOURCE 200809L (or _DEFAULT_SOURCE)
 * before its first #include, as every file using a clock here does.
 */
#ifndef CM_CLOCK_H
#define CM_CLOCK_H

#include <stdint.h>
#include <time.h>

#ifndef CLOCK_MONOTONIC
#error "cm_clock.h needs CLOCK_MONOTONIC: define _POSIX_C_SOURCE 200809L before the first #include"
#endif

/** CLOCK_MONOTONIC now. */
static inline struct timespec cm_clock_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts;
}

/** Milliseconds of CLOCK_MONOTONIC (from an unspecified start; whole milliseconds, rounded down). */
static inline int64_t cm_clock_ms(void)
{
    struct timespec ts = cm_clock_now();
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/** Seconds of CLOCK_MONOTONIC to the nanosecond, for timing reports. */
static inline double cm_clock_s(void)
{
    struct timespec ts = cm_clock_now();
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif /* CM_CLOCK_H */
