/*
 * fuzz_iges - libFuzzer target for the whole IGES import: file layer,
 * entity geometry, B-rep, face domains and curve mesh.  Any input must end
 * in CM_OK or a clear error, never a crash, a hang or a leak.  Built with
 * clang -fsanitize=fuzzer,address,undefined (make fuzz-iges); replayed
 * without libFuzzer by replay_main.c in make check.
 *
 * "Clear" is checked, not hoped for: a failure (other than out of memory)
 * must leave a message that names the place in the input ("line N" or
 * "DE N"), and so must every warning (a file line, or a DE in its text).
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "iges/iges_geom.h"
#include "model_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int names_place(const char *msg)
{
    return strstr(msg, "line ") != NULL || strstr(msg, "DE ") != NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* subfigure DAGs that place up to the product's 2^18 faces are legal and take minutes (each
       placed face is one more copy through the same code): the fuzzer refuses them at 4096, so its
       time goes to inputs that reach new code (the budget's refusal path is still reached) */
    iges_max_placed_faces = 4096;
    if (size > (4u << 20))
        return 0; /* keep each run short: larger inputs add nothing the corpus does not cover */
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    /* as cmz encode loads it: placed copies folded out (brep_fold_instances sees the hostile
       instances' transforms) */
    cm_err e = model_load_data_ex("fuzz", (const char *)data, size, &lm, MODEL_LOAD_FOLD, NULL, NULL, &st);
    if (e != CM_OK && e != CM_E_NOMEM && (lm.iges.err[0] == 0 || !names_place(lm.iges.err))) {
        fprintf(stderr, "fuzz_iges: %s without a place in the input: \"%s\" [%s]\n", cm_err_name(e), lm.iges.err,
                st.where ? st.where : "");
        __builtin_trap(); /* a failure must always say why, and where */
    }
    for (int i = 0; i < lm.iges.nwarn; i++)
        if (lm.iges.warn[i].line <= 0 && !names_place(lm.iges.warn[i].msg)) {
            fprintf(stderr, "fuzz_iges: a warning without a place in the input: \"%s\"\n", lm.iges.warn[i].msg);
            __builtin_trap();
        }
    model_free(&lm);
    return 0;
}
