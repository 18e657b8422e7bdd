/*
 * replay - run a fuzz target's LLVMFuzzerTestOneInput over files and
 * directories without libFuzzer (lz4's standaloneengine idea), so gcc and
 * CI replay the corpus and the regression inputs.  Each input gets
 * 20 s plus 1 s per 10 kB of wall-clock time, at most REPLAY_TIMEOUT
 * seconds (default 400), via alarm(): a hang is a failure too (SQLite
 * fuzzcheck's setAlarm).  Scaled by size so that a small input which runs
 * for minutes (a 35 kB subfigure DAG placing 2^18 faces) fails, while the
 * corpus's 2.5 MB assembly has the time it needs under ASan.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char *current = "";

static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "replay: timeout on ";
    if (write(2, msg, sizeof msg - 1) < 0 || write(2, current, strlen(current)) < 0 || write(2, "\n", 1) < 0)
        _exit(3);
    _exit(3);
}

static int run_file(const char *path, unsigned timeout)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        return -1;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *buf = malloc(n > 0 ? (size_t)n : 1);
    if (!buf || (n > 0 && fread(buf, 1, (size_t)n, f) != (size_t)n)) {
        fclose(f);
        free(buf);
        fprintf(stderr, "replay: cannot read %s\n", path);
        return -1;
    }
    fclose(f);
    current = path;
    unsigned limit = 20u + (unsigned)(n / 10000);
    alarm(limit < timeout ? limit : timeout);
    LLVMFuzzerTestOneInput(buf, (size_t)n);
    alarm(0);
    free(buf);
    return 0;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv)
{
    /* a hang detector, not a speed test: the 2.5 MB, 27734-face assembly of the corpus takes about
       a minute under ASan on an idle 2-core machine and over two when the machine is busy */
    unsigned timeout = getenv("REPLAY_TIMEOUT") ? (unsigned)atoi(getenv("REPLAY_TIMEOUT")) : 400;
    signal(SIGALRM, on_alarm);
    int count = 0, bad = 0;
    for (int i = 1; i < argc; i++) {
        struct stat sb;
        if (stat(argv[i], &sb) != 0) {
            perror(argv[i]);
            bad++;
            continue;
        }
        if (!S_ISDIR(sb.st_mode)) {
            bad += run_file(argv[i], timeout) != 0;
            count++;
            continue;
        }
        DIR *d = opendir(argv[i]);
        if (!d) {
            perror(argv[i]);
            bad++;
            continue;
        }
        char **names = NULL;
        int nn = 0;
        struct dirent *de;
        while ((de = readdir(d)) != NULL) {
            if (de->d_name[0] == '.')
                continue;
            names = realloc(names, (size_t)(nn + 1) * sizeof *names);
            size_t l = strlen(argv[i]) + strlen(de->d_name) + 2;
            names[nn] = malloc(l);
            snprintf(names[nn], l, "%s/%s", argv[i], de->d_name);
            nn++;
        }
        closedir(d);
        qsort(names, (size_t)nn, sizeof *names, cmp_str);
        for (int k = 0; k < nn; k++) {
            bad += run_file(names[k], timeout) != 0;
            count++;
            free(names[k]);
        }
        free(names);
    }
    printf("replay: %d inputs, %d unreadable\n", count, bad);
    return bad ? 1 : 0;
}
