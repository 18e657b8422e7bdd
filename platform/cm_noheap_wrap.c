/*
 * cm_noheap_wrap.c - abort on any heap call: the terminal's programs
 * (cmz-decode, cmz-terminal) and the unit tests link with
 * -Wl,--wrap=malloc,... (NOHEAP_WRAP in the Makefile), so a malloc, calloc,
 * realloc, free, aligned_alloc or posix_memalign made by project code lands
 * here and the process aborts, naming the call.
 *
 * Why in the product: the terminal build never touches the heap on its
 * decode path (every buffer is static and sized by fixedcfg, see
 * cm_decode_state.h), and this is a security property, not only a test: a
 * hostile file cannot make the board allocate, exhaust memory or reach a
 * use-after-free, and a heap call that a later change lets in fails loudly
 * on the first run instead of shipping.  It is also layer (b) of the no-heap
 * gate (layer (a): tests/tools/check_noheap.sh on the decoder archive).
 * Calls made inside shared libraries (libc's own, libusb, libgpiod,
 * libcmocka) are not wrapped: --wrap only redirects the references of the
 * objects being linked.
 */
#include <stdio.h>
#include <stdlib.h>

void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t m);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);
void *__wrap_aligned_alloc(size_t a, size_t n);
int __wrap_posix_memalign(void **p, size_t a, size_t n);

static void heap_used(const char *fn)
{
    fprintf(stderr, "no-heap gate: project code called %s\n", fn);
    abort();
}

void *__wrap_malloc(size_t n)
{
    (void)n;
    heap_used("malloc");
    return NULL;
}

void *__wrap_calloc(size_t n, size_t m)
{
    (void)n;
    (void)m;
    heap_used("calloc");
    return NULL;
}

void *__wrap_realloc(void *p, size_t n)
{
    (void)p;
    (void)n;
    heap_used("realloc");
    return NULL;
}

void __wrap_free(void *p)
{
    (void)p;
    heap_used("free");
}

void *__wrap_aligned_alloc(size_t a, size_t n)
{
    (void)a;
    (void)n;
    heap_used("aligned_alloc");
    return NULL;
}

int __wrap_posix_memalign(void **p, size_t a, size_t n)
{
    (void)p;
    (void)a;
    (void)n;
    heap_used("posix_memalign");
    return 12;
}
