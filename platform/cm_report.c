/* cm_report.c - human-readable limits tables and error lines. */
#include "cm_report.h"

#include "cm/cm_method.h"

#include <errno.h>
#include <string.h>

#include "cm/cm_decode_state.h"
#include "cm/cm_limits_info.h"

void cm_report_limits(FILE *f)
{
    fprintf(f, "curvemesh limits, profile %s\n", cm_profile_name);
    fprintf(f, "%-18s %12s %12s  %-10s %s\n", "limit", "value", "hard max", "unit", "meaning");
    for (unsigned i = 0; i < CM_LIMIT_COUNT; i++) {
        const cm_limit_info *l = &cm_limit_table[i];
        fprintf(f, "%-18s %12lu %12lu  %-10s %s\n", l->name, (unsigned long)l->value, (unsigned long)l->hard_max,
                l->unit, l->doc);
    }
    /* not limits of a model: the memory one decode takes at these limits (cm_decode_state.h) */
    unsigned long long budget = (unsigned long long)CM_DECODE_STATE_BUDGET;
#if CM_DECODE_STATE_FITS
    unsigned long long size = (unsigned long long)sizeof(cm_decode_state);
    fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f MiB)\n", "decode state", size, "", "bytes",
            "static storage of one decode: decoder, triangulator, mesh", (double)size / 1048576.0);
    /* where it goes (issue 15: what a smaller board must give up first) */
    const cm_decode_state *s = NULL;
    const struct {
        const char *name, *doc;
        unsigned long long bytes;
    } part[] = {
        {"  file", "the .cmz's window: its header, then its sections read again", sizeof s->dec.buf},
        {"  model", "the decoded model: curves, pools, faces, copies", sizeof s->dec.model},
        {"  predictors", "vertices and one kept net on the integer grid", sizeof s->dec.vq + sizeof s->dec.sq + sizeof s->dec.sw},
        {"  triangulator", "one face's tessellation workspace", sizeof s->tess},
        {"  output mesh", "the mesh's window (one face's tessellation), its faces and spill pages",
         sizeof s->pos + sizeof s->nrm + sizeof s->idx + sizeof s->faces + sizeof s->spill},
    };
    for (size_t i = 0; i < sizeof part / sizeof part[0]; i++)
        fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f MiB)\n", part[i].name, part[i].bytes, "", "bytes", part[i].doc,
                (double)part[i].bytes / 1048576.0);
#else
    fprintf(f, "%-18s %12s %12s  %-10s %s\n", "decode state", "-", "", "bytes",
            "larger than this target's address space: not declared here");
#endif
    fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f MiB)\n", "decode budget", budget, "", "bytes",
            "CM_DECODE_STATE_BUDGET, checked at compile time", (double)budget / 1048576.0);
    unsigned long long program = (unsigned long long)CM_PROGRAM_STATIC_BUDGET;
    fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f MiB)\n", "program budget", program, "", "bytes",
            "CM_PROGRAM_STATIC_BUDGET: a terminal program's other static storage (make check-ram)",
            (double)program / 1048576.0);
}

void cm_report_program_ram(FILE *f, const cm_ram_part *part, size_t n)
{
    unsigned long long sum = 0;
    for (size_t i = 0; i < n; i++) {
        fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f KiB)\n", part[i].name, part[i].bytes, "", "bytes", part[i].doc,
                (double)part[i].bytes / 1024.0);
        sum += part[i].bytes;
    }
    fprintf(f, "%-18s %12llu %12s  %-10s %s (%.1f KiB of %.1f KiB)\n", "program's own", sum, "", "bytes",
            "its static storage beside the decode state, the parts above", (double)sum / 1024.0,
            (double)CM_PROGRAM_STATIC_BUDGET / 1024.0);
}

void cm_report_limits_markdown(FILE *f)
{
    fprintf(f, "| limit | %s | hard max | unit | meaning |\n|---|---:|---:|---|---|\n", cm_profile_name);
    for (unsigned i = 0; i < CM_LIMIT_COUNT; i++) {
        const cm_limit_info *l = &cm_limit_table[i];
        fprintf(f, "| `CM_%s` | %lu | %lu | %s | %s |\n", l->name, (unsigned long)l->value, (unsigned long)l->hard_max,
                l->unit, l->doc);
    }
}

void cm_report_errors_markdown(FILE *f)
{
    fprintf(f, "| code | name | meaning |\n|---:|---|---|\n");
    for (int e = 0; e < (int)CM_ERR_COUNT; e++)
        if (cm_err_defined(e))
            fprintf(f, "| %d | `%s` | %s |\n", e, cm_err_name((cm_err)e), cm_strerror((cm_err)e));
}

char *cm_format_status(char *buf, size_t cap, const cm_status *st)
{
    size_t n = 0;
    int w;
#define APPEND(...)                                                              \
    do {                                                                         \
        w = snprintf(buf + n, n < cap ? cap - n : 0, __VA_ARGS__);               \
        if (w > 0)                                                               \
            n += (size_t)w;                                                      \
    } while (0)
    if (cap == 0)
        return buf;
    buf[0] = 0;
    if (st->face != CM_NO_FACE_INDEX)
        APPEND("face %lu, ", (unsigned long)st->face);
    if (st->offset != CM_NO_OFFSET)
        APPEND("byte %lu: ", (unsigned long)st->offset);
    APPEND("%s (%s)", cm_strerror(st->code), cm_err_name(st->code));
    if (st->code == CM_E_LIMIT) {
        const cm_limit_info *l = cm_limit_get(st->limit);
        if (l)
            APPEND(": needs %s=%llu, this build (profile %s) has %llu", l->name, (unsigned long long)st->need,
                   cm_profile_name, (unsigned long long)st->have);
    } else if (st->code == CM_E_NOSPACE) {
        APPEND(": needs %llu, buffer has %llu", (unsigned long long)st->need, (unsigned long long)st->have);
    }
    if (st->sys_errno)
        APPEND(": %s", strerror(st->sys_errno));
    if (st->where)
        APPEND(" [in %s]", st->where);
#undef APPEND
    if (n >= cap)
        buf[cap - 1] = 0;
    return buf;
}

cm_err cm_fail_errno(cm_status *st, const char *where)
{
    int err = errno;
    cm_err e = cm_fail(st, CM_E_IO, where);
    if (st && st->code == CM_E_IO && st->sys_errno == 0)
        st->sys_errno = err;
    return e;
}

void cm_report_status(FILE *f, const char *prog, const char *subject, const cm_status *st)
{
    char buf[512];
    cm_format_status(buf, sizeof buf, st);
    fprintf(f, "%s%s%s%s%s\n", prog ? prog : "", prog ? ": " : "", subject ? subject : "", subject ? ": " : "", buf);
}

char *cm_report_method_counts(char *buf, size_t cap, const uint32_t *count, int key_value)
{
    size_t n = 0;
    if (cap == 0)
        return buf;
    buf[0] = '\0';
    for (int i = 0; i < CM_METHOD_COUNT && n < cap; i++) {
        const cm_method *M = cm_method_table[i];
        int w = key_value ? snprintf(buf + n, cap - n, "%s%s=%lu", i ? " " : "", M->counted, (unsigned long)count[M->id])
                          : snprintf(buf + n, cap - n, "%s%lu %s", i ? ", " : "", (unsigned long)count[M->id], M->counted);
        if (w < 0)
            break;
        n += (size_t)w;
    }
    return buf;
}
