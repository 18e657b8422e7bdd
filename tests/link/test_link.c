/*
 * test_link.c - the link protocol without cables: frames and messages over
 * memory, then whole transfers between a terminal (a child process running
 * cm_link_term in a temporary directory) and link_send over a socketpair,
 * through the fault decorator.  TAP output.
 *
 *   test_link SEED.cmzf     (a decode fuzz seed: one chunking byte, then a valid .cmz; make
 *                            check-link gives a format 3 one: two tests edit its header by the
 *                            fixed offsets of format 3's, and the link carries any format alike)
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cm/cm_arith.h"
#include "cm/cm_crc32.h"
#include "cm/cm_format.h"
#include "cm_link.h"
#include "cm_link_term.h"
#include "cm_transport_fd.h"
#include "fake/cm_transport_fault.h"
#include "fake/cm_transport_mem.h"
#include "send/link_send.h"
#include "link_harness.h"


static uint8_t wire[1 << 20];
static cm_link la, lb;

/* ---- frames over memory ---- */

/* the next frame, past the early returns that report a damaged one */
static int recv_next(cm_link *l, cm_link_frame *f)
{
    int r = 0;
    for (int i = 0; i < 10 && r == 0; i++)
        r = cm_link_recv(l, f, 100);
    return r;
}
static void test_frames(void)
{
    cm_memlink out;
    cm_mem_open(&out, NULL, 0, wire, sizeof wire, CM_MEM_END_HANGUP);
    cm_link_init(&la, &out.t);
    uint8_t p[300];
    for (int i = 0; i < 300; i++)
        p[i] = (uint8_t)(i * 7);
    int s1 = cm_link_send(&la, CM_LINK_DATA, -1, p, 300, 100);
    int s2 = cm_link_send(&la, CM_LINK_END, 9, p, 8, 100);
    size_t one = out.out_len;
    /* garbage, a frame with a flipped payload byte, a frame with a bad length, then a good one */
    uint8_t stream[4096];
    size_t k = 0;
    const char junk[] = "\xC5\x4Dnoise\xC5";
    memcpy(stream + k, junk, sizeof junk - 1);
    k += sizeof junk - 1;
    memcpy(stream + k, wire, one);
    stream[k + 20] ^= 0x10; /* payload damaged: CRC fails */
    k += one;
    memcpy(stream + k, wire, 12);
    stream[k + 5] ^= 0x40; /* length damaged: the header check fails */
    k += 12;
    memcpy(stream + k, wire, one);
    k += one;
    cm_memlink in;
    cm_mem_open(&in, stream, k, NULL, 0, CM_MEM_END_HANGUP);
    in.read_chunk = 7; /* frames arrive in pieces */
    cm_link_init(&lb, &in.t);
    /* what survives: the first END, then the second DATA and END */
    cm_link_frame f;
    int r1 = recv_next(&lb, &f);
    int good = r1 == 1 && f.type == CM_LINK_END && f.seq == 9;
    int r2 = recv_next(&lb, &f);
    good = good && r2 == 1 && f.type == CM_LINK_DATA && f.len == 300 && memcmp(f.payload, p, 300) == 0;
    int r3 = recv_next(&lb, &f);
    good = good && r3 == 1 && f.type == CM_LINK_END && f.seq == 9 && f.len == 8;
    int r4 = recv_next(&lb, &f);
    tap(s1 == 1 && s2 == 1 && good && r4 == CM_T_HANGUP && lb.stats.bad_crc >= 1 && lb.stats.bad_header >= 1,
        "frames: resynchronised past garbage, a bad CRC and a bad length (bad_crc %llu, bad_header %llu, skipped %llu)",
        (unsigned long long)lb.stats.bad_crc, (unsigned long long)lb.stats.bad_header,
        (unsigned long long)lb.stats.skipped);
}

static void test_messages(void)
{
    cm_link_hello h, g;
    cm_link_hello_local(&h, "bench-7");
    uint8_t p[1024];
    size_t n = cm_link_hello_pack(&h, p);
    cm_link_frame f = {CM_LINK_HELLO, 0, (uint16_t)n, p};
    int ok = cm_link_hello_unpack(&f, &g) && g.nlimits == CM_LIMIT_COUNT && strcmp(g.name, "bench-7") == 0 &&
             g.limit[CM_LIMIT_MAX_FACES] == CM_MAX_FACES && g.fmt_major_max == h.fmt_major_max;
    f.len = (uint16_t)(n - 1);
    int short_rejected = !cm_link_hello_unpack(&f, &g);
    tap(ok && short_rejected, "HELLO: limits, versions and name round-trip; a short payload is rejected");
    {
        /* the HELLO in pieces (issue 11 #4): asked for by SYNC, collected in any order, duplicates and a
           piece of another terminal's HELLO among them; the next SYNC asks only for what is missing */
        static cm_link_hello_parts parts;
        cm_link_hello_parts_reset(&parts);
        uint8_t s[CM_LINK_SYNC_BYTES], q[4 + CM_LINK_HELLO_PIECE];
        unsigned first = 9;
        uint32_t mask = 0;
        cm_link_frame sf = {CM_LINK_SYNC, 0, (uint16_t)cm_link_sync_pack(&parts, s), s};
        int asks_all = cm_link_sync_unpack(&sf, &first, &mask) == 1 && first == 0 && mask == 0xFFFFFFFFu;
        uint8_t plain[1] = {CM_LINK_PROTO};
        cm_link_frame pf = {CM_LINK_SYNC, 0, 1, plain};
        int plain_whole = cm_link_sync_unpack(&pf, &first, &mask) == 0;
        unsigned count = (unsigned)((n + CM_LINK_HELLO_PIECE - 1) / CM_LINK_HELLO_PIECE);
        cm_link_hello other;
        cm_link_hello_local(&other, "bench-8");
        uint8_t op[1024];
        size_t on = cm_link_hello_pack(&other, op);
        int done = 0, early = 0;
        memset(&g, 0, sizeof g);
        for (unsigned i = 0; i < count; i++) {
            unsigned k = count - 1 - i; /* last piece first */
            if (i == 1) {               /* a piece of bench-8's HELLO: restarts the collection */
                cm_link_frame of = {CM_LINK_HELLO_PART, 0, (uint16_t)cm_link_hello_part_pack(op, on, 0, q), q};
                (void)cm_link_hello_part_add(&parts, &of, &g);
            }
            cm_link_frame qf = {CM_LINK_HELLO_PART, 0, (uint16_t)cm_link_hello_part_pack(p, n, k, q), q};
            int r = cm_link_hello_part_add(&parts, &qf, &g);
            (void)cm_link_hello_part_add(&parts, &qf, &g); /* the same piece twice */
            if (r && k != 0)
                early = 1;
            if (i == count / 2) {
                /* half in: the SYNC asks for the pieces below and for the last one (the foreign piece dropped
                   it), not for those held */
                sf.len = (uint16_t)cm_link_sync_pack(&parts, s);
                int a = cm_link_sync_unpack(&sf, &first, &mask);
                early |= a != 1 || first != 0 || (mask >> (count - 2) & 1u) || !(mask & 1u) ||
                         !(mask >> (count - 1) & 1u);
            }
            done = r;
        }
        /* the pieces of the foreign HELLO's piece 0 restart made the ones before it vanish: ask again */
        for (unsigned k = 0; !done && k < count; k++) {
            cm_link_frame qf = {CM_LINK_HELLO_PART, 0, (uint16_t)cm_link_hello_part_pack(p, n, k, q), q};
            done = cm_link_hello_part_add(&parts, &qf, &g);
        }
        cm_link_frame bad = {CM_LINK_HELLO_PART, 0, (uint16_t)cm_link_hello_part_pack(p, n, count, q), q};
        tap(asks_all && plain_whole && !early && done && strcmp(g.name, "bench-7") == 0 &&
                g.nlimits == CM_LIMIT_COUNT && g.limit[CM_LIMIT_MAX_FACES] == CM_MAX_FACES && bad.len == 0 &&
                CM_LINK_HELLO_PIECE + 16u <= 24u,
            "HELLO in %u pieces of %u bytes (24-byte frames): any order, duplicates and a foreign piece, the SYNC "
            "asking only for the missing ones; a 1-byte SYNC still asks for the whole HELLO",
            count, CM_LINK_HELLO_PIECE);
    }
    cm_link_offer o = {123456, 0xdeadbeef, 512, 0x0123456789abcdefull, "part 7.cmz"}, q;
    n = cm_link_offer_pack(&o, p);
    f = (cm_link_frame){CM_LINK_OFFER, 0, (uint16_t)n, p};
    ok = cm_link_offer_unpack(&f, &q) && q.size == o.size && q.crc == o.crc && q.chunk == 512 &&
         q.id == o.id && strcmp(q.name, o.name) == 0;
    p[12] = 200; /* a name length beyond the payload */
    tap(ok && !cm_link_offer_unpack(&f, &q), "OFFER round-trips; a lying name length is rejected");
    /* the content id: CRC-64/XZ's check value, and two valid .cmz-like files (each ending with the
       CRC-32 of what precedes it) get different ids though their whole-file CRC-32 is the same */
    uint8_t a[12] = "abcdefgh", b[12] = "abcdefgX";
    cm_link_put32(a + 8, cm_crc32(a, 8));
    cm_link_put32(b + 8, cm_crc32(b, 8));
    const uint8_t check[] = "123456789";
    tap(cm_link_id_update(0, check, 9) == 0x995DC9BBDF1939FAull && cm_crc32(a, 12) == cm_crc32(b, 12) &&
            cm_link_id_update(0, a, 12) != cm_link_id_update(0, b, 12) &&
            cm_link_id_update(cm_link_id_update(0, a, 5), a + 5, 7) == cm_link_id_update(0, a, 12),
        "content id: CRC-64/XZ check value; same-size files with the same CRC-32 residue differ");
}

/* ---- whole transfers: terminal in a child process ---- */

static cm_decoder term_dec;
static cm_link_term term;

/* the child: serve until a model was received and checked, then exit 0 (or the failure code) */
static int run_terminal(int fd, const char *dir, double noise, uint64_t seed, int exit_after_bytes)
{
    static cm_fdlink fl;
    static cm_fault fault;
    if (cm_fd_open(&fl, fd, fd, "socket") != 0)
        return 90;
    cm_fault_config fc = {noise, noise, 0, -1, 0, seed};
    if (cm_fault_open(&fault, &fl.t, &fc) != 0)
        return 91;
    if (cm_link_term_open(&term, &term_dec, dir, "test-terminal") != 0)
        return 92;
    cm_link_term_attach(&term, &fault.t);
    for (;;) {
        int ev = cm_link_term_poll(&term, exit_after_bytes ? 0 : 200); /* 0: one frame per call */
        if (ev < 0)
            return 93;
        if (exit_after_bytes && term.prefix >= (uint32_t)exit_after_bytes) {
            cm_link_term_close(&term); /* a restart (SIGTERM, reboot): what it holds is synced */
            _exit(0);
        }
        if (ev == CM_TERM_FAILED)
            return 10;
        if (ev == CM_TERM_COMPLETE) {
            cm_status st;
            cm_status_init(&st);
            int code = cm_dec_finish(&term_dec, &st);
            cm_link_term_decoded(&term, code, code ? "decode failed" : "decoded");
            /* stay a moment to answer a repeated END */
            for (int i = 0; i < 5; i++)
                (void)cm_link_term_poll(&term, 100);
            return code ? 11 : 0;
        }
    }
}

static int spawn_terminal(int *sv, const char *dir, double noise, uint64_t seed, int exit_after_bytes)
{
    if (socketpair(AF_UNIX, SOCK_STREAM, 0, sv) != 0)
        return -1;
    pid_t pid = fork();
    if (pid == 0) {
        close(sv[0]);
        _exit(run_terminal(sv[1], dir, noise, seed, exit_after_bytes));
    }
    close(sv[1]);
    return (int)pid;
}



static void test_transfer(const uint8_t *data, uint32_t size, const char *dir, double noise, const char *what)
{
    int sv[2];
    int pid = spawn_terminal(sv, dir, noise, 11, 0);
    static cm_fdlink fl;
    static cm_fault fault;
    cm_fd_open(&fl, sv[0], sv[0], "socket");
    cm_fault_config fc = {noise, noise, 0, -1, 0, 5};
    cm_fault_open(&fault, &fl.t, &fc);
    static cm_link l;
    cm_link_init(&l, &fault.t);
    link_send_opts o;
    test_send_opts(&o);
    link_send_result r;
    int rc = link_send_file(&l, data, size, "seed.cmz", &o, &r);
    close(sv[0]);
    int crc = wait_child(pid);
    char path[600];
    snprintf(path, sizeof path, "%s/.incoming.cmz", dir);
    tap(rc == 0 && crc == 0 && r.stage == CM_LINK_STAGE_DECODED && file_equals(path, data, size),
        "transfer %s: %u bytes, sender %d, terminal %d, %llu chunks (%llu again), chunk changes %u, %u reconnects%s%s",
        what, (unsigned)size, rc, crc, (unsigned long long)r.chunks_sent, (unsigned long long)r.chunks_resent,
        r.chunk_changes, r.reconnects, rc ? ": " : "", rc ? r.text : "");
    unlink(path);
}

/* one send over a clean socket to a fresh terminal in dir: the sender's code; *child, the terminal's */
static int send_once(const uint8_t *data, uint32_t size, const char *name, const char *dir, link_send_result *r,
                     int *child)
{
    int sv[2];
    int pid = spawn_terminal(sv, dir, 0, 1, 0);
    static cm_fdlink fl;
    cm_fd_open(&fl, sv[0], sv[0], "socket");
    static cm_link l;
    cm_link_init(&l, &fl.t);
    link_send_opts o;
    test_send_opts(&o);
    int rc = link_send_file(&l, data, size, name, &o, r);
    close(sv[0]);
    *child = wait_child(pid);
    return rc;
}

static void test_refused_in_stream(const uint8_t *data, uint32_t size, const char *dir)
{
    /* the header says the model needs one face more than this build has; CRC fixed up */
    static uint8_t bad[1 << 20];
    memcpy(bad, data, size);
    uint32_t h = cm_link_get32(bad + CM_HDR_LENGTH);
    cm_link_put32(bad + cm_fmt_need_at(CM_LIMIT_MAX_FACES), CM_MAX_FACES + 1u);
    cm_link_put32(bad + h - 4, cm_crc32(bad, h - 4));
    link_send_result r;
    int crc;
    int rc = send_once(bad, size, "too-big.cmz", dir, &r, &crc);
    struct stat s;
    char path[600];
    snprintf(path, sizeof path, "%s/.incoming.part", dir);
    tap(rc == 1 && crc == 10 && strstr(r.text, "MAX_FACES") && r.code == CM_E_LIMIT && stat(path, &s) != 0,
        "a model over the terminal's MAX_FACES is refused once its header is in, naming the limit: %s", r.text);
}

/* a transfer of `first` cut by a terminal restart after a third of it, then a send of `second` to the
   restarted terminal (64-byte chunks): the two sends' codes, the terminals' exits, the second's result */
typedef struct cut_send {
    int rc1, c1, rc2, c2;
    link_send_result r;
} cut_send;

static void send_cut_then(const uint8_t *first, const uint8_t *second, uint32_t size, const char *dir, cut_send *cs)
{
    int sv[2];
    int pid = spawn_terminal(sv, dir, 0, 1, (int)(size / 3));
    static cm_fdlink fl;
    cm_fd_open(&fl, sv[0], sv[0], "socket");
    static cm_link l;
    cm_link_init(&l, &fl.t);
    link_send_opts o;
    test_send_opts(&o);
    o.connect_timeout_ms = 1500;
    o.chunk = 64;
    cs->rc1 = link_send_file(&l, first, size, "first.cmz", &o, &cs->r);
    close(sv[0]);
    cs->c1 = wait_child(pid);
    pid = spawn_terminal(sv, dir, 0, 1, 0);
    cm_fd_open(&fl, sv[0], sv[0], "socket");
    cm_link_init(&l, &fl.t);
    o.connect_timeout_ms = 15000; /* the new terminal answers as soon as it runs: on a busy machine, later */
    cs->rc2 = link_send_file(&l, second, size, "second.cmz", &o, &cs->r);
    close(sv[0]);
    cs->c2 = wait_child(pid);
}

static void test_resume(const uint8_t *data, uint32_t size, const char *dir)
{
    /* the terminal restarts after a third of the file; the new one resumes from its synced prefix */
    cut_send cs;
    send_cut_then(data, data, size, dir, &cs);
    char path[600];
    snprintf(path, sizeof path, "%s/.incoming.cmz", dir);
    tap(cs.rc1 == -1 && cs.c1 == 0 && cs.rc2 == 0 && cs.c2 == 0 && cs.r.resumes == 1 && cs.r.resume_offset > 0 &&
            file_equals(path, data, size),
        "a terminal restarted after %u bytes: the next one resumes at byte %u, file identical", (unsigned)(size / 3),
        (unsigned)cs.r.resume_offset);
    unlink(path);
}

/* issue 11 #1: a terminal holding part of one file is offered another valid .cmz of the same size
   (same whole-file CRC-32, as every .cmz has): it must start over, not splice the two */
static void test_resume_other_file(const uint8_t *data, uint32_t size, const char *dir)
{
    static uint8_t other[1 << 20];
    memcpy(other, data, size);
    uint32_t h = cm_link_get32(other + CM_HDR_LENGTH);
    other[CM_HDR_TESS_TOL + 7] ^= 0x01; /* the recommended chordal tolerance, in the header: a different model file */
    cm_link_put32(other + h - 4, cm_crc32(other, h - 4));
    cm_link_put32(other + size - 4, cm_crc32(other, size - 4));
    cut_send cs;
    send_cut_then(data, other, size, dir, &cs);
    char path[600];
    snprintf(path, sizeof path, "%s/.incoming.cmz", dir);
    tap(cs.rc1 == -1 && cs.c1 == 0 && cm_crc32(data, size) == cm_crc32(other, size) && cs.rc2 == 0 && cs.c2 == 0 &&
            cs.r.resumes == 0 && cs.r.resumed_from == 0 && file_equals(path, other, size),
        "another file of the same size and CRC-32 after a cut: not resumed (from byte %u, %u resumes), the second "
        "file stored whole",
        (unsigned)cs.r.resumed_from, cs.r.resumes);
    unlink(path);
}

/* issue 11: the free-space check at OFFER counted the .cmz twice and not the GLB it decodes to (about
   30 times its size), so a good model on a nearly full disk ended as rejected.cmz.  The directory is
   made to look 100 kB free (CM_TERM_FREE_BYTES): enough for the old check (2 x 7411 + 64 KiB), not
   for the GLB.  And an empty offer is called invalid, not "needs MAX_FILE_BYTES=0". */
static void test_offer_refusals(const uint8_t *data, uint32_t size, const char *dir)
{
    setenv("CM_TERM_FREE_BYTES", "100000", 1); /* read by the terminal child at the offer */
    link_send_result r;
    int c;
    int rc = send_once(data, size, "full-disk.cmz", dir, &r, &c);
    unsetenv("CM_TERM_FREE_BYTES");
    tap(rc == 1 && c == 10 && strstr(r.text, "no space") && strstr(r.text, "GLB"),
        "a disk with room for the .cmz but not its GLB: refused at the offer, saying so: %s", r.text);
    /* an empty offer, straight to a terminal */
    int sv[2];
    int pid = spawn_terminal(sv, dir, 0, 1, 0);
    static cm_fdlink fl;
    static cm_link l;
    cm_fd_open(&fl, sv[0], sv[0], "socket");
    cm_link_init(&l, &fl.t);
    uint8_t p[CM_LINK_MAX_PAYLOAD];
    cm_link_offer of = {0, 0, 256, 0, "empty.cmz"};
    cm_link_frame f;
    int got = 0;
    char text[CM_LINK_MAX_TEXT + 1] = "";
    int code = 0;
    for (int i = 0; i < 20 && !got; i++) {
        (void)cm_link_send(&l, CM_LINK_OFFER, -1, p, cm_link_offer_pack(&of, p), 1000);
        while (!got && cm_link_recv(&l, &f, 500) == 1)
            got = f.type == CM_LINK_REFUSE && cm_link_text_unpack(&f, 0, NULL, &code, text, sizeof text);
    }
    close(sv[0]);
    c = wait_child(pid);
    tap(got && code == CM_E_PROTOCOL && strstr(text, "size 0") && !strstr(text, "MAX_FILE_BYTES"),
        "an empty offer is refused as invalid, not as over MAX_FILE_BYTES: %s (code %d)", text, code);
}

/* --write-seeds: what a terminal's cable delivers for a whole transfer of data (SYNC, OFFER, DATA
   in 256-byte chunks, END), clean, with 1 % noise, and cut in the middle: seeds for fuzz_link */
static int write_seeds(const uint8_t *data, uint32_t size, const char *dir)
{
    static uint8_t buf[1 << 20], noisy[1 << 20];
    cm_memlink m;
    cm_mem_open(&m, NULL, 0, buf + 1, sizeof buf - 1, CM_MEM_END_HANGUP);
    cm_link_init(&la, &m.t);
    uint8_t p[CM_LINK_MAX_PAYLOAD];
    p[0] = CM_LINK_PROTO;
    (void)cm_link_send(&la, CM_LINK_SYNC, -1, p, 1, 100);
    cm_link_offer o = {size, cm_crc32(data, size), 256, cm_link_id_update(0, data, size), "seed.cmz"};
    (void)cm_link_send(&la, CM_LINK_OFFER, -1, p, cm_link_offer_pack(&o, p), 100);
    for (uint32_t off = 0; off < size; off += 256) {
        uint32_t n = size - off < 256 ? size - off : 256;
        cm_link_put32(p, off);
        memcpy(p + 4, data + off, n);
        (void)cm_link_send(&la, CM_LINK_DATA, -1, p, n + 4, 100);
    }
    cm_link_put32(p, size);
    cm_link_put32(p + 4, o.crc);
    cm_link_put64(p + 8, o.id);
    (void)cm_link_send(&la, CM_LINK_END, -1, p, CM_LINK_END_BYTES, 100);
    buf[0] = 63; /* read in 64-byte pieces */
    size_t len = m.out_len + 1;
    cm_fault_noise z;
    cm_fault_noise_init(&z, 0.01, 0.01, 0.005, 3);
    size_t used = 0;
    noisy[0] = 16;
    size_t nl = 1 + cm_fault_noise_apply(&z, buf + 1, len - 1, &used, noisy + 1, sizeof noisy - 1);
    struct { const char *name; const uint8_t *b; size_t n; } seeds[] = {
        {"transfer_clean.link", buf, len}, {"transfer_noisy.link", noisy, nl}, {"transfer_cut.link", buf, len / 2}};
    for (size_t i = 0; i < sizeof seeds / sizeof seeds[0]; i++) {
        char path[600];
        snprintf(path, sizeof path, "%s/%s", dir, seeds[i].name);
        FILE *f = fopen(path, "wb");
        if (!f || fwrite(seeds[i].b, 1, seeds[i].n, f) != seeds[i].n || fclose(f) != 0) {
            fprintf(stderr, "test_link: cannot write %s\n", path);
            return 1;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    signal(SIGPIPE, SIG_IGN);
    /* a protocol regression tends to livelock (two ends re-offering forever), not to fail: end it
       (SIGALRM, a failure for the runner) well before CI's own timeout.  The whole suite takes ~2 s */
    alarm(120);
    if (argc != 2 && !(argc == 4 && strcmp(argv[2], "--write-seeds") == 0)) {
        fprintf(stderr, "usage: test_link SEED.cmzf [--write-seeds DIR]\n");
        return 2;
    }
    uint32_t size;
    const uint8_t *data = read_seed("test_link", argv[1], &size);
    if (!data)
        return 2;
    if (argc == 4)
        return write_seeds(data, size, argv[3]);
    char dir[] = "/tmp/cm-test-link-XXXXXX";
    if (!mkdtemp(dir))
        return 2;
    test_frames();
    test_messages();
    test_transfer(data, size, dir, 0, "on a clean line");
    test_transfer(data, size, dir, 0.01, "through 1 % dropped and 1 % corrupted bytes each way");
    test_refused_in_stream(data, size, dir);
    test_resume(data, size, dir);
    test_resume_other_file(data, size, dir);
    test_offer_refusals(data, size, dir);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "test_link: could not remove %s\n", dir);
    printf("%d passed, %d failed\n", n_test - n_fail, n_fail);
    return n_fail ? 1 : 0;
}
