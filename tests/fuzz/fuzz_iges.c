/*
 * fuzz_iges - libFuzzer target for the whole IGES import: file layer,
 * entity geometry, B-rep, face domains and curve mesh.  Any input must end
 * in CM_OK or a clear error, never a crash, a hang or a leak.  Built with
 * clang -fsanitize=fuzzer,address,undefined (make fuzz-iges); replayed
 * without libFuzzer by replay_main.c in make check.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "model_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > (4u << 20))
        return 0; /* keep each run short: larger inputs add nothing the corpus does not cover */
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    cm_err e = model_load_data("fuzz", (const char *)data, size, &lm, NULL, NULL, &st);
    if (e != CM_OK && e != CM_E_IO && lm.iges.err[0] == 0 && st.code == CM_OK)
        __builtin_trap(); /* a failure must always say why */
    model_free(&lm);
    return 0;
}
