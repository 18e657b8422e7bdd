/*
 * fuzz_link - libFuzzer target for the terminal's end of the link: the
 * input is everything the cable delivers (frames, garbage, half frames),
 * served by a memory transport in pieces whose sizes the input also picks,
 * to a cm_link_term storing into a scratch directory, with every COMPLETE
 * decoded as cmz-terminal does.  Whatever arrives must end in a clean
 * state: no crash, no hang, no write outside the directory, and a file is
 * only ever moved to .incoming.cmz after its CRC matched.
 *
 * First byte: read size (1..256).  Built with clang -fsanitize=fuzzer
 * (make fuzz-link); replayed without libFuzzer in make check
 * (check-fuzz-link-replay, seeds written by test_link --write-seeds).
 */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cm_link_term.h"
#include "fake/cm_transport_mem.h"

static int read_again(void *ctx, uint32_t off, uint8_t *buf, size_t n)
{
    return pread(*(const int *)ctx, buf, n, (off_t)off) == (ssize_t)n ? 0 : -1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static cm_decoder dec;
static cm_link_term term;
static uint8_t sink[1 << 16];
static char dir[64];

static void clean_dir(void)
{
    static const char *const names[] = {".incoming.part", ".incoming.meta", ".incoming.meta.tmp", ".incoming.cmz"};
    char p[128];
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        unlink(p);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/cm-fuzz-link-XXXXXX");
        if (!mkdtemp(dir))
            abort();
    }
    if (size < 1)
        return 0;
    clean_dir();
    static cm_memlink m;
    cm_mem_open(&m, data + 1, size - 1, sink, sizeof sink, CM_MEM_END_HANGUP);
    m.read_chunk = (size_t)data[0] + 1;
    if (cm_link_term_open(&term, &dec, dir, "fuzz") != 0)
        abort();
    cm_link_term_attach(&term, &m.t);
    /* bounded: every call consumes input or ends at the hang-up */
    for (int round = 0; round < 100000; round++) {
        int ev = cm_link_term_poll(&term, 0);
        if (ev < 0)
            break;
        if (ev == CM_TERM_COMPLETE) {
            cm_status st;
            cm_status_init(&st);
            /* a file longer than the decoder's window is read again from where the link stored it */
            static int fd;
            fd = open(term.in_path, O_RDONLY | O_CLOEXEC);
            if (fd >= 0)
                cm_dec_set_source(&dec, read_again, &fd);
            int code = cm_dec_finish(&dec, &st);
            if (fd >= 0)
                close(fd);
            cm_link_term_decoded(&term, code, code ? "decode failed" : "decoded");
        }
        if (m.in_pos >= m.in_len && ev == CM_TERM_NONE && term.link.start == term.link.end)
            break;
    }
    cm_link_term_close(&term);
    return 0;
}
