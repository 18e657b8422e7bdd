/* cm_transport_mem.c - a byte link over two memory buffers (see cm_transport_mem.h). */
#include "cm_transport_mem.h"

#include <stdio.h>
#include <string.h>

static long closed_fail(cm_memlink *m, const char *op)
{
    snprintf(m->t.err, sizeof m->t.err, "%s: %s after close", m->t.name, op);
    return CM_T_IO;
}

/* t is the first member (C11 6.7.2.1p15), so the back end's struct starts where t does;
 * the cast goes through void * because -Wcast-align cannot know that */
static cm_memlink *memlink_of(cm_transport *t)
{
    return (cm_memlink *)(void *)t;
}

static long mem_read(cm_transport *t, uint8_t *buf, size_t n, int timeout_ms)
{
    cm_memlink *m = memlink_of(t);
    (void)timeout_ms; /* memory never makes anyone wait */
    m->reads++;
    if (m->closed)
        return closed_fail(m, "read");
    if (n == 0)
        return 0;
    size_t left = m->in_len - m->in_pos;
    if (left == 0) {
        if (m->at_end == CM_MEM_END_TIMEOUT)
            return 0;
        snprintf(t->err, sizeof t->err, "%s: end of input (%zu bytes)", t->name, m->in_len);
        return CM_T_HANGUP;
    }
    size_t k = left < n ? left : n;
    if (m->read_chunk && k > m->read_chunk)
        k = m->read_chunk;
    memcpy(buf, m->in + m->in_pos, k);
    m->in_pos += k;
    return (long)k;
}

static long mem_write(cm_transport *t, const uint8_t *buf, size_t n, int timeout_ms)
{
    cm_memlink *m = memlink_of(t);
    (void)timeout_ms;
    m->writes++;
    if (m->closed)
        return closed_fail(m, "write");
    size_t room = m->out_cap - m->out_len;
    size_t k = n < room ? n : room;
    if (k)
        memcpy(m->out + m->out_len, buf, k);
    m->out_len += k;
    m->overflow += n - k;
    return (long)n;
}

static void mem_close(cm_transport *t)
{
    (memlink_of(t))->closed = 1;
}

void cm_mem_open(cm_memlink *m, const uint8_t *in, size_t in_len, uint8_t *out, size_t out_cap, cm_mem_end at_end)
{
    memset(m, 0, sizeof *m);
    m->t.read = mem_read;
    m->t.write = mem_write;
    m->t.close = mem_close;
    snprintf(m->t.name, sizeof m->t.name, "mem");
    m->in = in;
    m->in_len = in ? in_len : 0;
    m->out = out;
    m->out_cap = out ? out_cap : 0;
    m->at_end = at_end;
}
