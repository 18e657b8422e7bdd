/*
 * gpio_probe.c - drive the terminal's GPIO lines by hand, through cm_gpio
 * exactly as the terminal does; tests/hw/vm-gpio.sh runs it against gpio-sim.
 *
 *   gpio_probe [--busy SPEC] [--ready SPEC] [--error SPEC] [--request SPEC]
 *              [--consumer NAME] [COMMAND...]
 *
 * Commands run in order after cm_gpio_open; with none, they are read from
 * standard input, one a line, and each is answered with one line on standard
 * output (so a test can drive the probe as a coprocess and check the lines
 * between two commands):
 *   set busy|ready|error 0|1   drive an output            -> "set busy 1"
 *   wait-press MS              wait up to MS for the button -> "pressed" or "no press"
 *   pressed                    check without waiting        -> "pressed" or "no press"
 *   sleep MS                   pause                        -> "slept MS"
 *   quit                       close and exit               -> "bye"
 * A failed command answers "error: TEXT" and, from the command line, ends
 * the program.  Exit: 0 success; 1 open or command failed (text on stderr);
 * 2 a wait-press given on the command line saw no press; 64 usage.
 */
#define _POSIX_C_SOURCE 200809L

#include "cm_gpio.h"

#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { EXIT_USAGE = 64, CMD_WORDS = 4, LINE_MAX_LEN = 256 };

static void usage(void) {
    fputs("usage: gpio_probe [--busy SPEC] [--ready SPEC] [--error SPEC] [--request SPEC] [--consumer NAME]\n"
          "                  [set LINE 0|1 | wait-press MS | pressed | sleep MS | quit]...\n"
          "  SPEC is [!]CHIP:LINE (CHIP: gpiochip0, /dev/gpiochip0 or a label; LINE: a name or an offset)\n",
          stderr);
}

/** Milliseconds of the monotonic clock. */
static long long now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/** Parse a non-negative decimal number of milliseconds; -1 if it is not one. */
static long parse_ms(const char *s) {
    if (!s || !*s) return -1;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    return (*end || errno || v < 0 || v > 3600000L) ? -1 : v;
}

/** Wait up to ms for a request edge. @return 1 pressed, 0 not, -1 error (text in g->err) */
static int wait_press(cm_gpio *g, long ms) {
    int fd = cm_gpio_request_fd(g);
    if (fd < 0) {
        snprintf(g->err, sizeof g->err, "no request line configured (--request SPEC)");
        return -1;
    }
    long long deadline = now_ms() + ms;
    for (;;) {
        int pressed = cm_gpio_request_pressed(g);
        if (pressed != 0) return pressed;
        long long left = deadline - now_ms();
        if (left <= 0) return 0;
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        if (poll(&pfd, 1, (int)left) < 0 && errno != EINTR) {
            snprintf(g->err, sizeof g->err, "poll on the request line: %s", strerror(errno));
            return -1;
        }
    }
}

/** Run one command of argc words. @return 0 ok, 1 failed, 2 no press, 3 quit */
static int run_command(cm_gpio *g, int argc, char **argv) {
    const char *cmd = argv[0];
    if (strcmp(cmd, "set") == 0 && argc == 3) {
        static const char *const names[CM_GPIO_NOUT] = {"busy", "ready", "error"};
        int which = -1;
        for (int i = 0; i < CM_GPIO_NOUT; i++)
            if (strcmp(argv[1], names[i]) == 0) which = i;
        if (which < 0 || (strcmp(argv[2], "0") != 0 && strcmp(argv[2], "1") != 0)) {
            printf("error: set LINE VALUE: LINE is busy, ready or error, VALUE is 0 or 1\n");
            return 1;
        }
        if (cm_gpio_set(g, (cm_gpio_line)which, argv[2][0] == '1') < 0) {
            printf("error: %s\n", g->err);
            return 1;
        }
        printf("set %s %s\n", argv[1], argv[2]);
        return 0;
    }
    if ((strcmp(cmd, "wait-press") == 0 && argc == 2) || (strcmp(cmd, "pressed") == 0 && argc == 1)) {
        long ms = argc == 2 ? parse_ms(argv[1]) : 0;
        if (ms < 0) {
            printf("error: wait-press MS: MS is a number of milliseconds\n");
            return 1;
        }
        int r = wait_press(g, ms);
        if (r < 0) {
            printf("error: %s\n", g->err);
            return 1;
        }
        printf("%s\n", r ? "pressed" : "no press");
        return r ? 0 : 2;
    }
    if (strcmp(cmd, "sleep") == 0 && argc == 2) {
        long ms = parse_ms(argv[1]);
        if (ms < 0) {
            printf("error: sleep MS: MS is a number of milliseconds\n");
            return 1;
        }
        struct timespec ts = {.tv_sec = ms / 1000, .tv_nsec = (ms % 1000) * 1000000L};
        while (nanosleep(&ts, &ts) < 0 && errno == EINTR) {
        }
        printf("slept %ld\n", ms);
        return 0;
    }
    if (strcmp(cmd, "quit") == 0 && argc == 1) {
        printf("bye\n");
        return 3;
    }
    printf("error: unknown command '%s' (or wrong number of words)\n", cmd);
    return 1;
}

/** Commands from standard input, one a line; ends at EOF or quit. */
static int run_stdin(cm_gpio *g) {
    char buf[LINE_MAX_LEN];
    while (fgets(buf, sizeof buf, stdin)) {
        char *words[CMD_WORDS];
        int n = 0;
        for (char *save = NULL, *w = strtok_r(buf, " \t\r\n", &save); w; w = strtok_r(NULL, " \t\r\n", &save)) {
            if (n == CMD_WORDS) {
                n = CMD_WORDS + 1;
                break;
            }
            words[n++] = w;
        }
        if (n == 0) continue;
        if (n > CMD_WORDS) {
            printf("error: too many words\n");
            continue;
        }
        if (run_command(g, n, words) == 3) break;
    }
    return 0;
}

/** How many words the command at argv[0] takes, itself included; 0 if unknown. */
static int command_words(char **argv, int left) {
    const char *c = argv[0];
    int n = strcmp(c, "set") == 0 ? 3 : (strcmp(c, "wait-press") == 0 || strcmp(c, "sleep") == 0) ? 2
                                    : (strcmp(c, "pressed") == 0 || strcmp(c, "quit") == 0)       ? 1
                                                                                                  : 0;
    return n <= left ? n : 0;
}

int main(int argc, char **argv) {
    cm_gpio_config cfg = {.consumer = "gpio_probe"};
    int i = 1;
    for (; i < argc && strncmp(argv[i], "--", 2) == 0; i += 2) {
        const char *opt = argv[i];
        if (strcmp(opt, "--help") == 0) {
            usage();
            return 0;
        }
        if (i + 1 >= argc) {
            usage();
            return EXIT_USAGE;
        }
        const char *val = argv[i + 1];
        if (strcmp(opt, "--busy") == 0) cfg.out[CM_GPIO_BUSY] = val;
        else if (strcmp(opt, "--ready") == 0) cfg.out[CM_GPIO_READY] = val;
        else if (strcmp(opt, "--error") == 0) cfg.out[CM_GPIO_ERROR] = val;
        else if (strcmp(opt, "--request") == 0) cfg.request = val;
        else if (strcmp(opt, "--consumer") == 0) cfg.consumer = val;
        else {
            usage();
            return EXIT_USAGE;
        }
    }
    setvbuf(stdout, NULL, _IOLBF, 0);

    static cm_gpio g;
    if (cm_gpio_open(&g, &cfg) < 0) {
        fprintf(stderr, "gpio_probe: %s\n", g.err);
        return 1;
    }
    int status = 0;
    if (i == argc) {
        status = run_stdin(&g);
    } else {
        while (i < argc) {
            int n = command_words(argv + i, argc - i);
            if (n == 0) {
                fprintf(stderr, "gpio_probe: unknown command or missing argument at '%s'\n", argv[i]);
                status = EXIT_USAGE;
                break;
            }
            int r = run_command(&g, n, argv + i);
            i += n;
            if (r == 3) break;
            if (r != 0) {
                status = r;
                break;
            }
        }
    }
    cm_gpio_close(&g);
    cm_gpio_close(&g); /* the header promises that a second close is harmless */
    return status;
}
