/*
 * fuzz_step - libFuzzer target for the whole STEP import: Part 21 file layer, entity geometry and
 * topology, units, colours, assembly placements, face domains and curve mesh.  Any input must end
 * in CM_OK or a clear error, never a crash, a hang or a leak.  Built with clang
 * -fsanitize=fuzzer,address,undefined (make fuzz-step); replayed without libFuzzer by
 * replay_main.c in make check.
 *
 * "Clear" is checked: a failure (other than out of memory) must name a place in the input (a
 * "line N" or an instance "#N"), and so must every warning.  Inputs that are not STEP (the IGES
 * reader's business, fuzzed by fuzz_iges) are passed over.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "model_load.h"
#include "step/step_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int names_place(const char *msg)
{
    return strstr(msg, "line ") != NULL || strchr(msg, '#') != NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > (4u << 20) || !step_sniff((const char *)data, size))
        return 0;
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    /* as cmz encode loads it: placed copies folded out */
    cm_err e = model_load_data_ex("fuzz", (const char *)data, size, &lm, MODEL_LOAD_FOLD, NULL, NULL, &st);
    if (e != CM_OK && e != CM_E_NOMEM && (lm.iges.err[0] == 0 || !names_place(lm.iges.err))) {
        fprintf(stderr, "fuzz_step: %s without a place in the input: \"%s\" [%s]\n", cm_err_name(e), lm.iges.err,
                st.where ? st.where : "");
        __builtin_trap();
    }
    for (int i = 0; i < lm.iges.nwarn; i++)
        if (lm.iges.warn[i].line <= 0 && !names_place(lm.iges.warn[i].msg)) {
            fprintf(stderr, "fuzz_step: a warning without a place in the input: \"%s\"\n", lm.iges.warn[i].msg);
            __builtin_trap();
        }
    model_free(&lm);
    return 0;
}
