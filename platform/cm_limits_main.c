/*
 * cm-limits - print the compile-time limits and error codes of this build.
 *
 *   cm-limits               the limits table of the profile it was built with
 *   cm-limits --value NAME  one value (e.g. STACK_BUDGET), for scripts
 *   cm-limits --markdown    the limits table in Markdown (README)
 *   cm-limits --errors      the error table in Markdown (README)
 *   cm-limits --tsv         name, value, hard max, unit, meaning per line
 */
#include <stdio.h>
#include <string.h>

#include "cm/cm_limits_info.h"
#include "cm_report.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: cm-limits [--value NAME | --markdown | --tsv | --errors | --help]\n"
               "Print the compile-time limits (fixedcfg/) of this build, profile %s.\n",
            cm_profile_name);
}

int main(int argc, char **argv)
{
    if (argc == 1) {
        cm_report_limits(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--markdown") == 0 && argc == 2) {
        cm_report_limits_markdown(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--tsv") == 0 && argc == 2) {
        for (unsigned i = 0; i < CM_LIMIT_COUNT; i++) {
            const cm_limit_info *l = &cm_limit_table[i];
            printf("CM_%s\t%lu\t%lu\t%s\t%s\n", l->name, (unsigned long)l->value, (unsigned long)l->hard_max, l->unit,
                   l->doc);
        }
        return 0;
    }
    if (strcmp(argv[1], "--errors") == 0 && argc == 2) {
        cm_report_errors_markdown(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--value") == 0 && argc == 3) {
        for (unsigned i = 0; i < CM_LIMIT_COUNT; i++)
            if (strcmp(cm_limit_table[i].name, argv[2]) == 0) {
                printf("%lu\n", (unsigned long)cm_limit_table[i].value);
                return 0;
            }
        fprintf(stderr, "cm-limits: no limit named %s\n", argv[2]);
        return 2;
    }
    usage(stderr);
    return 2;
}
