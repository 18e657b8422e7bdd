/* cm_link_term.c - the terminal's end of a transfer (see cm_link_term.h, docs/LINK.md). */
#define _POSIX_C_SOURCE 200809L
#include "cm_link_term.h"

#include <errno.h>
#include <stdarg.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "cm/cm_crc32.h"
#include "cm_clock.h"
#include "cm_decode_file.h"
#include "cm_report.h"

#define META_MAGIC 0x32504C43u /* "CLP2": protocol 2's meta (with the content id); an older one is dropped */
#define META_BYTES 32u
/* An fsync costs 10-200 ms on an SD card (and on this VM's disk): done every second it stalls
   the link, which a noisy line then pays in timeouts.  A power cut loses at most 5 s of transfer;
   a stall, a hang-up or a clean stop syncs at once. */
#define SYNC_EVERY_MS 5000
#define SYNC_EVERY_BYTES (4u * 1024u * 1024u) /* time rules: an fsync per 256 KiB would throttle USB */

static int join(char *out, const char *dir, const char *name)
{
    int n = snprintf(out, CM_TERM_PATH, "%s/%s", dir, name);
    return n > 0 && n < CM_TERM_PATH ? 0 : -1;
}

/* snprintf into a message buffer, where cutting a long path short is fine */
__attribute__((format(printf, 3, 4))) static void textf(char *out, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, cap, fmt, ap);
    va_end(ap);
}

static void set_why(cm_link_term *t, const char *what, const char *detail)
{
    textf(t->why, sizeof t->why, "%s%s%s", what, detail ? ": " : "", detail ? detail : "");
}

/* ---- the meta file: size, crc, content id, synced prefix; CRC-protected, replaced atomically ---- */

static int meta_write(cm_link_term *t)
{
    uint8_t b[META_BYTES];
    cm_link_put32(b, META_MAGIC);
    cm_link_put32(b + 4, t->offer.size);
    cm_link_put32(b + 8, t->offer.crc);
    cm_link_put32(b + 12, t->synced);
    cm_link_put32(b + 16, (uint32_t)strlen(t->offer.name));
    cm_link_put64(b + 20, t->offer.id);
    cm_link_put32(b + 28, cm_crc32(b, 28));
    char tmp[CM_TERM_PATH];
    if (snprintf(tmp, sizeof tmp, "%s.tmp", t->meta_path) >= (int)sizeof tmp)
        return -1;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return -1;
    int ok = write(fd, b, sizeof b) == (ssize_t)sizeof b && fsync(fd) == 0;
    ok = close(fd) == 0 && ok;
    return ok && rename(tmp, t->meta_path) == 0 ? 0 : -1;
}

/* the transfer left by an earlier run: size, crc and synced prefix; its content id goes straight to t->offer */
static int meta_read(cm_link_term *t, uint32_t *size, uint32_t *crc, uint32_t *synced)
{
    uint8_t b[META_BYTES];
    int fd = open(t->meta_path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    ssize_t n = read(fd, b, sizeof b);
    close(fd);
    if (n != (ssize_t)sizeof b || cm_link_get32(b) != META_MAGIC || cm_link_get32(b + 28) != cm_crc32(b, 28))
        return -1;
    t->offer.id = cm_link_get64(b + 20);
    *size = cm_link_get32(b + 4);
    *crc = cm_link_get32(b + 8);
    *synced = cm_link_get32(b + 12);
    return 0;
}

static void drop_transfer(cm_link_term *t)
{
    if (t->part_fd >= 0)
        close(t->part_fd);
    t->part_fd = -1;
    unlink(t->part_path);
    unlink(t->meta_path);
    t->active = false;
}

/* make the synced prefix durable: data first, then the meta that vouches for it */
static void sync_prefix(cm_link_term *t, bool force)
{
    int64_t now = cm_clock_ms();
    if (!force && t->prefix - t->synced < SYNC_EVERY_BYTES && now - t->last_sync_ms < SYNC_EVERY_MS)
        return;
    if (t->prefix == t->synced && !force)
        return;
    if (t->part_fd >= 0 && fdatasync(t->part_fd) == 0) {
        uint32_t old = t->synced;
        t->synced = t->prefix;
        if (meta_write(t) != 0)
            t->synced = old;
    }
    t->last_sync_ms = now;
}

/* feed [from, to) of the part file to the decoder; a refusal ends the transfer */
static int feed(cm_link_term *t, uint32_t from, uint32_t to, cm_status *st)
{
    uint8_t buf[4096];
    while (from < to) {
        size_t n = to - from < sizeof buf ? to - from : sizeof buf;
        ssize_t r = pread(t->part_fd, buf, n, (off_t)from);
        if (r <= 0) {
            cm_status_init(st);
            (void)cm_fail(st, CM_E_IO, "read back of the incoming file");
            return -1;
        }
        if (cm_dec_feed(t->dec, buf, (size_t)r, st) != CM_OK)
            return -1;
        from += (uint32_t)r;
    }
    return 0;
}

static void send_text(cm_link_term *t, uint8_t type, int seq, int stage, int code, const char *text)
{
    uint8_t p[CM_LINK_MAX_TEXT + 2];
    size_t n = cm_link_text_pack(stage, code, text, p);
    (void)cm_link_send(&t->link, type, seq, p, n, 1000);
}

/* damaged frames seen on this link: what the sender sizes its chunks by */
static uint32_t damaged(const cm_link_term *t)
{
    return (uint32_t)(t->link.stats.bad_crc + t->link.stats.bad_header);
}

static void send_ack(cm_link_term *t, int seq)
{
    uint8_t p[16];
    cm_link_put32(p, t->prefix);
    cm_link_put32(p + 4, (uint32_t)t->held);
    cm_link_put32(p + 8, (uint32_t)(t->held >> 32));
    cm_link_put32(p + 12, damaged(t));
    t->last_ack_ms = cm_clock_ms();
    t->damage_reported = damaged(t);
    (void)cm_link_send(&t->link, CM_LINK_ACK, seq, p, sizeof p, 1000);
}

static void refuse(cm_link_term *t, int seq, int code, const char *text)
{
    set_why(t, "refused", text);
    send_text(t, CM_LINK_REFUSE, seq, -1, code, text);
}

static bool recover_verified(cm_link_term *t);
static void remember_shown(cm_link_term *t);

/*
 * Disk space a new model takes until it is shown: the part file (renamed, then hard-linked into
 * the new generation: it is never copied), the GLB and STL written beside the model on screen
 * (and the decoded mesh spilled beside them while they are written)
 * (the old generation is removed only after the swap), and 64 KiB for the meta file, directories
 * and symlinks.  The GLB and STL are not known before the file is decoded: cm_out_bytes_bound
 * estimates them from the size (cm_decode_file.h says how, and when it falls short).
 */
static uint64_t store_need(const cm_link_term *t, uint32_t size)
{
    /* the mesh's spill (cm_decode_file.c) is on disk while the outputs are written: its positions,
       normals and indices are what a GLB's binary chunk holds, so the GLB's bound bounds it too */
    uint64_t need = (uint64_t)size + 2u * cm_out_bytes_bound(CM_OUT_GLB, size) + 65536u;
    if (t->writes_stl)
        need += cm_out_bytes_bound(CM_OUT_STL, size);
    return need;
}

int cm_link_term_open(cm_link_term *t, cm_decoder *dec, const char *dir, const char *name)
{
    memset(t, 0, sizeof *t);
    t->dec = dec;
    t->part_fd = -1;
    cm_link_hello_local(&t->hello, name);
    struct stat s;
    if (strlen(dir) >= sizeof t->dir || join(t->part_path, dir, ".incoming.part") || join(t->meta_path, dir, ".incoming.meta") ||
        join(t->in_path, dir, ".incoming.cmz")) {
        set_why(t, "output directory path too long", dir);
        return -1;
    }
    if (stat(dir, &s) != 0 || !S_ISDIR(s.st_mode) || access(dir, W_OK) != 0) {
        set_why(t, "output directory is not a writable directory", dir);
        return -1;
    }
    strcpy(t->dir, dir);
    char tmp[CM_TERM_PATH + 8];
    snprintf(tmp, sizeof tmp, "%s.tmp", t->meta_path);
    unlink(tmp); /* meta_write killed before its rename */
    /* a file verified and stored whole but killed before it was decoded: the caller finishes it.
       The terminal decodes .incoming.cmz before it serves another frame, so a part file beside it
       is older (the same transfer's meta, a kill before its unlink): dropped */
    if (recover_verified(t)) {
        drop_transfer(t);
        return 0;
    }
    remember_shown(t);
    /* a transfer left by an earlier run: keep it to resume from its synced prefix */
    uint32_t size, crc, synced;
    if (meta_read(t, &size, &crc, &synced) == 0) {
        int fd = open(t->part_path, O_RDWR | O_CLOEXEC);
        struct stat ps;
        if (fd >= 0 && fstat(fd, &ps) == 0 && (uint64_t)ps.st_size >= synced && synced <= size) {
            t->part_fd = fd;
            t->active = true;
            t->offer.size = size;
            t->offer.crc = crc;
            t->prefix = t->synced = t->origin = synced;
            t->chunk = 0; /* set by the next OFFER */
            cm_dec_init(t->dec);
            cm_status st;
            cm_status_init(&st);
            if (feed(t, 0, synced, &st) != 0)
                drop_transfer(t);
        } else {
            if (fd >= 0)
                close(fd);
            drop_transfer(t);
        }
    } else {
        unlink(t->part_path);
    }
    return 0;
}

void cm_link_term_attach(cm_link_term *t, cm_transport *tr)
{
    cm_link_init(&t->link, tr);
}

void cm_link_term_close(cm_link_term *t)
{
    if (t->active)
        sync_prefix(t, true);
    if (t->part_fd >= 0)
        close(t->part_fd);
    t->part_fd = -1;
}

/* the part file of the transfer in progress is open (cm_link_term_close, at a hang-up, closed it) */
static int ensure_part(cm_link_term *t)
{
    if (t->part_fd < 0)
        t->part_fd = open(t->part_path, O_RDWR | O_CLOEXEC);
    return t->part_fd >= 0 ? 0 : -1;
}

static int on_offer(cm_link_term *t, const cm_link_frame *f)
{
    cm_link_offer o;
    if (!cm_link_offer_unpack(f, &o))
        return CM_TERM_NONE;
    char text[CM_LINK_MAX_TEXT + 1];
    if (o.size == 0) {
        refuse(t, f->seq, CM_E_PROTOCOL, "invalid offer: size 0 (an empty file holds no model)");
        return CM_TERM_FAILED;
    }
    if (o.size > CM_MAX_FILE_BYTES) {
        snprintf(text, sizeof text,
                 "exceeds a compile-time limit of this build (CM_E_LIMIT): the model needs MAX_FILE_BYTES=%u, this "
                 "build (profile %s) has %u",
                 (unsigned)o.size, cm_profile_name, (unsigned)CM_MAX_FILE_BYTES);
        refuse(t, f->seq, CM_E_LIMIT, text);
        return CM_TERM_FAILED;
    }
    uint32_t chunk = o.chunk;
    if (chunk == 0 || chunk > CM_LINK_MAX_PAYLOAD - 4)
        chunk = CM_LINK_MAX_PAYLOAD - 4;
    /* resume only the same file: same size and content id (the CRC-32 alone is the same for every .cmz) */
    bool same = t->active && o.size == t->offer.size && o.crc == t->offer.crc && o.id == t->offer.id;
    int ev = CM_TERM_NONE;
    if (!same) {
        struct statvfs v;
        uint64_t need = store_need(t, o.size);
        uint64_t free_bytes = statvfs(t->dir, &v) == 0 ? (uint64_t)v.f_bavail * v.f_frsize : UINT64_MAX;
        /* fault injection, like CM_TERM_KILL_AT (cm_kill_point.h): CM_TERM_FREE_BYTES=N makes the
           directory look N bytes free, so the tests reach this refusal without a full disk */
        const char *fake = getenv("CM_TERM_FREE_BYTES");
        if (fake && *fake)
            free_bytes = strtoull(fake, NULL, 10);
        if (free_bytes < need) {
            textf(text, sizeof text, "no space: %s has %llu bytes free, the model needs up to %llu (%u for the .cmz, "
                  "the rest for the %s it decodes to)", t->dir, (unsigned long long)free_bytes,
                  (unsigned long long)need, (unsigned)o.size, t->writes_stl ? "GLB and STL" : "GLB");
            refuse(t, f->seq, CM_E_IO, text);
            return CM_TERM_FAILED;
        }
        drop_transfer(t);
        t->part_fd = open(t->part_path, O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (t->part_fd < 0) {
            textf(text, sizeof text, "cannot create %s: %s", t->part_path, strerror(errno));
            refuse(t, f->seq, CM_E_IO, text);
            return CM_TERM_FAILED;
        }
        t->offer = o;
        t->prefix = t->synced = 0;
        t->active = true;
        t->last_sync_ms = cm_clock_ms();
        cm_dec_init(t->dec);
        /* no meta yet: the first sync writes it (before that there is nothing worth resuming) */
        ev = CM_TERM_STARTED;
    } else {
        if (ensure_part(t) != 0) {
            textf(text, sizeof text, "cannot reopen %s: %s", t->part_path, strerror(errno));
            drop_transfer(t);
            refuse(t, f->seq, CM_E_IO, text);
            return CM_TERM_FAILED;
        }
        memcpy(t->offer.name, o.name, sizeof o.name);
        if (t->chunk == 0)
            ev = CM_TERM_STARTED; /* resumed after a restart */
    }
    /* (re)start the chunk grid at the contiguous prefix; chunks held beyond it are fetched again */
    t->origin = t->prefix;
    t->chunk = chunk;
    t->held = 0;
    t->idle_reported = false;
    uint8_t p[CM_LINK_ACCEPT_BYTES];
    cm_link_put32(p, t->prefix);
    cm_link_put32(p + 4, chunk);
    cm_link_put32(p + 8, o.crc);
    cm_link_put64(p + 12, o.id);
    (void)cm_link_send(&t->link, CM_LINK_ACCEPT, f->seq, p, sizeof p, 1000);
    return ev;
}

static int on_data(cm_link_term *t, const cm_link_frame *f)
{
    if (!t->active || t->chunk == 0 || f->len < 4 || ensure_part(t) != 0) {
        if (t->active)
            send_ack(t, f->seq);
        return CM_TERM_NONE; /* no offer accepted yet: the sender will offer again */
    }
    uint32_t off = cm_link_get32(f->payload), n = f->len - 4u;
    uint32_t size = t->offer.size;
    if (off < t->prefix || off >= size) {
        send_ack(t, f->seq); /* a duplicate: our ACK was lost */
        return CM_TERM_NONE;
    }
    uint32_t rel = off - t->prefix;
    if ((off - t->origin) % t->chunk != 0 || rel / t->chunk >= CM_LINK_WINDOW ||
        n != (size - off < t->chunk ? size - off : t->chunk)) {
        send_ack(t, f->seq); /* off the grid (an old offer's chunk size) or beyond the window */
        return CM_TERM_NONE;
    }
    unsigned j = rel / t->chunk;
    if (!(t->held >> j & 1u)) {
        if (pwrite(t->part_fd, f->payload + 4, n, (off_t)off) != (ssize_t)n) {
            char text[CM_LINK_MAX_TEXT + 1];
            textf(text, sizeof text, "cannot write %s: %s", t->part_path, strerror(errno));
            drop_transfer(t);
            refuse(t, f->seq, CM_E_IO, text);
            return CM_TERM_FAILED;
        }
        t->held |= (uint64_t)1 << j;
    }
    uint32_t old = t->prefix;
    while (t->held & 1u) {
        uint32_t len = size - t->prefix < t->chunk ? size - t->prefix : t->chunk;
        t->prefix += len;
        t->held >>= 1;
    }
    if (t->prefix != old) {
        cm_status st;
        cm_status_init(&st);
        if (feed(t, old, t->prefix, &st) != 0) {
            char text[CM_LINK_MAX_TEXT + 1];
            cm_format_status(text, sizeof text, &st);
            int code = st.code;
            drop_transfer(t);
            refuse(t, f->seq, code, text);
            return CM_TERM_FAILED;
        }
        sync_prefix(t, false);
    }
    send_ack(t, f->seq);
    return CM_TERM_NONE;
}

/* CRC-32 and content id of the stored bytes; false if they cannot be read back */
static bool file_check(int fd, uint32_t size, uint32_t *crc, uint64_t *id)
{
    uint8_t buf[4096];
    uint32_t at = 0;
    *crc = 0;
    *id = 0;
    while (at < size) {
        size_t n = size - at < sizeof buf ? size - at : sizeof buf;
        ssize_t r = pread(fd, buf, n, (off_t)at);
        if (r <= 0)
            return false;
        *crc = cm_crc32_update(*crc, buf, (size_t)r);
        *id = cm_link_id_update(*id, buf, (size_t)r);
        at += (uint32_t)r;
    }
    return true;
}

static void remember(cm_link_term *t, int stage, int code, const char *text)
{
    t->have_last = true;
    t->last_size = t->offer.size;
    t->last_crc = t->offer.crc;
    t->last_id = t->offer.id;
    t->last_stage = stage;
    t->last_code = code;
    textf(t->last_text, sizeof t->last_text, "%s", text);
}

static int on_end(cm_link_term *t, const cm_link_frame *f)
{
    if (f->len != CM_LINK_END_BYTES)
        return CM_TERM_NONE;
    uint32_t size = cm_link_get32(f->payload), crc = cm_link_get32(f->payload + 4);
    uint64_t id = cm_link_get64(f->payload + 8);
    if (!t->active || size != t->offer.size || crc != t->offer.crc || id != t->offer.id) {
        if (t->have_last && size == t->last_size && crc == t->last_crc && id == t->last_id)
            send_text(t, CM_LINK_DONE, f->seq, t->last_stage, t->last_code, t->last_text);
        else
            send_text(t, CM_LINK_ABORT, f->seq, -1, CM_E_FORMAT, "no such transfer in progress: offer it again");
        return CM_TERM_NONE;
    }
    if (t->prefix != size || ensure_part(t) != 0) {
        send_ack(t, f->seq);
        return CM_TERM_NONE;
    }
    uint32_t got;
    uint64_t got_id;
    bool ok = file_check(t->part_fd, size, &got, &got_id);
    char text[CM_LINK_MAX_TEXT + 1];
    if (!ok || got != crc || got_id != id) {
        /* the CRC catches damage; the id also catches another file's bytes (a resume gone wrong) */
        snprintf(text, sizeof text, "file CRC %08x id %016llx, the sender's %08x %016llx: received again from the start",
                 (unsigned)got, (unsigned long long)got_id, (unsigned)crc, (unsigned long long)id);
        remember(t, CM_LINK_STAGE_STORED, CM_E_CRC, text);
        set_why(t, "CRC mismatch", text);
        drop_transfer(t);
        send_text(t, CM_LINK_DONE, f->seq, CM_LINK_STAGE_STORED, CM_E_CRC, text);
        return CM_TERM_FAILED;
    }
    if (fsync(t->part_fd) != 0 || rename(t->part_path, t->in_path) != 0) {
        textf(text, sizeof text, "cannot store %s: %s", t->in_path, strerror(errno));
        remember(t, CM_LINK_STAGE_STORED, CM_E_IO, text);
        set_why(t, "store failed", text);
        drop_transfer(t);
        send_text(t, CM_LINK_DONE, f->seq, CM_LINK_STAGE_STORED, CM_E_IO, text);
        return CM_TERM_FAILED;
    }
    close(t->part_fd);
    t->part_fd = -1;
    unlink(t->meta_path);
    t->active = false;
    snprintf(text, sizeof text, "%u bytes stored, CRC %08x", (unsigned)size, (unsigned)crc);
    remember(t, CM_LINK_STAGE_STORED, 0, text);
    send_text(t, CM_LINK_DONE, f->seq, CM_LINK_STAGE_STORED, 0, text);
    return CM_TERM_COMPLETE;
}

int cm_link_term_poll(cm_link_term *t, int timeout_ms)
{
    int64_t deadline = cm_clock_ms() + timeout_ms;
    for (;;) {
        int64_t left = deadline - cm_clock_ms();
        if (left < 0)
            left = 0;
        cm_link_frame f;
        int r = cm_link_recv(&t->link, &f, (int)left);
        if (r < 0)
            return r;
        int64_t now = cm_clock_ms();
        /* frames arriving damaged: say so (at most every 20 ms), so that a sender whose chunks
           never arrive whole learns it without waiting for timeouts */
        if (t->active && t->chunk && damaged(t) != t->damage_reported && now - t->last_ack_ms >= 20)
            send_ack(t, -1);
        if (r == 0) {
            if (t->active && t->chunk && !t->idle_reported && now - t->last_frame_ms > CM_TERM_IDLE_MS) {
                t->idle_reported = true;
                sync_prefix(t, true);
                return CM_TERM_IDLE;
            }
            return CM_TERM_NONE;
        }
        t->last_frame_ms = now;
        t->idle_reported = false;
        int ev = CM_TERM_NONE;
        switch (f.type) {
        case CM_LINK_SYNC: {
            uint8_t p[8 + 4 * CM_LIMIT_COUNT + CM_LINK_MAX_NAME], q[4 + CM_LINK_HELLO_PIECE];
            size_t n = cm_link_hello_pack(&t->hello, p);
            unsigned first = 0;
            uint32_t mask = 0;
            int ask = cm_link_sync_unpack(&f, &first, &mask);
            if (ask == 0)
                (void)cm_link_send(&t->link, CM_LINK_HELLO, f.seq, p, n, 1000);
            /* the pieces asked for (a noisy line: docs/LINK.md, "Finding the terminal") */
            for (unsigned j = 0; ask == 1 && j < 32; j++) {
                size_t m = mask >> j & 1u ? cm_link_hello_part_pack(p, n, first + j, q) : 0;
                if (m)
                    (void)cm_link_send(&t->link, CM_LINK_HELLO_PART, f.seq, q, m, 1000);
            }
            break;
        }
        case CM_LINK_OFFER:
            ev = on_offer(t, &f);
            break;
        case CM_LINK_DATA:
            ev = on_data(t, &f);
            break;
        case CM_LINK_END:
            ev = on_end(t, &f);
            break;
        case CM_LINK_ABORT:
            if (t->active)
                sync_prefix(t, true); /* the sender gave up: keep what we have for a resume */
            break;
        default:
            break; /* frames for the other end, or from a newer protocol: ignored */
        }
        if (ev != CM_TERM_NONE)
            return ev;
        if (cm_clock_ms() >= deadline)
            return CM_TERM_NONE;
    }
}

void cm_link_term_decoded(cm_link_term *t, int code, const char *text)
{
    remember(t, CM_LINK_STAGE_DECODED, code, text);
    send_text(t, CM_LINK_DONE, -1, CM_LINK_STAGE_DECODED, code, text);
}

int cm_link_term_request(cm_link_term *t)
{
    return cm_link_send(&t->link, CM_LINK_REQUEST, -1, NULL, 0, 1000);
}

/* t->offer's size, CRC and id from a whole .cmz file at path; false if there is none */
static bool identify(cm_link_term *t, const char *path)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return false;
    struct stat s;
    bool ok = fstat(fd, &s) == 0 && S_ISREG(s.st_mode) && s.st_size > 0 && s.st_size <= CM_MAX_FILE_BYTES;
    if (ok) {
        t->offer.size = (uint32_t)s.st_size;
        ok = file_check(fd, t->offer.size, &t->offer.crc, &t->offer.id);
    }
    close(fd);
    return ok;
}

/* .incoming.cmz left by a kill between its rename (after the CRC matched) and its decode */
static bool recover_verified(cm_link_term *t)
{
    t->recovered = identify(t, t->in_path);
    if (!t->recovered) {
        unlink(t->in_path); /* none, or not what a verified transfer leaves: nothing to finish */
        memset(&t->offer, 0, sizeof t->offer);
        return false;
    }
    /* what the sender's repeated END names it by (cm_link_term_recovered remembers it) */
    snprintf(t->offer.name, sizeof t->offer.name, ".incoming.cmz");
    return true;
}

/*
 * The model on screen, as if its transfer had just finished: a kill after it was shown but before
 * its DONE went out leaves a sender repeating END, and it is answered that the model is decoded.
 */
static void remember_shown(cm_link_term *t)
{
    char path[CM_TERM_PATH + 16];
    snprintf(path, sizeof path, "%s/model.cmz", t->dir);
    if (identify(t, path))
        remember(t, CM_LINK_STAGE_DECODED, 0, "on screen (decoded before the terminal restarted)");
    memset(&t->offer, 0, sizeof t->offer);
}

void cm_link_term_recovered(cm_link_term *t, int code, const char *text)
{
    remember(t, CM_LINK_STAGE_DECODED, code, text);
    t->recovered = false;
}
