/*
 * wall_min.c - the best wall time of a command, or of two commands run in turns (benchmarks only).
 *
 *   wall_min RUNS -- CMD [ARG...]                  prints "A_SECONDS"
 *   wall_min RUNS -- CMD_A [ARG...] -- CMD_B [ARG...]  prints "A_SECONDS B_SECONDS"
 *
 * Each command runs RUNS times (A, B, A, B, ... so that both see the same moments of a noisy
 * machine), its output thrown away; the time is from fork to wait, taken with CLOCK_MONOTONIC in
 * this process.  The benchmarks used to time a run between two `date` calls in the shell: that
 * counted the second `date`'s fork and exec, about 1-2 ms, on both sides of a ratio whose small
 * models take 2-10 ms, and pulled every decode ratio towards 1.  Exit 1 (and nothing printed) if
 * any run fails.
 */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* one run of argv, output to /dev/null; its wall seconds, or -1 if it did not exit 0 */
static double run_once(char **argv)
{
    double start = now();
    pid_t pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, 1);
            dup2(null, 2);
        }
        execvp(argv[0], argv);
        _exit(127);
    }
    int status;
    while (waitpid(pid, &status, 0) < 0)
        ;
    double end = now();
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? end - start : -1;
}

int main(int argc, char **argv)
{
    if (argc < 4 || strcmp(argv[2], "--") != 0) {
        fprintf(stderr, "usage: wall_min RUNS -- CMD [ARG...] [-- CMD_B [ARG...]]\n");
        return 2;
    }
    int runs = atoi(argv[1]);
    if (runs < 1)
        runs = 1;
    char **cmd[2] = {argv + 3, NULL};
    for (int i = 3; i < argc; i++)
        if (strcmp(argv[i], "--") == 0) {
            argv[i] = NULL;
            cmd[1] = argv + i + 1;
            break;
        }
    int ncmd = cmd[1] != NULL && cmd[1][0] != NULL ? 2 : 1;
    double best[2] = {-1, -1};
    for (int r = 0; r < runs; r++)
        for (int c = 0; c < ncmd; c++) {
            double t = run_once(cmd[c]);
            if (t < 0) {
                fprintf(stderr, "wall_min: %s failed\n", cmd[c][0]);
                return 1;
            }
            if (best[c] < 0 || t < best[c])
                best[c] = t;
        }
    if (ncmd == 2)
        printf("%.6f %.6f\n", best[0], best[1]);
    else
        printf("%.6f\n", best[0]);
    return 0;
}
