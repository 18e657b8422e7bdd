/*
 * noheap_wrap.c - no-heap gate, layer (b): unit tests link with
 * -Wl,--wrap=malloc,... so any heap call made by project code lands here
 * and aborts the test (cmocka's own allocations, inside libcmocka, are
 * not wrapped).
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

void *__wrap_malloc(size_t n) { (void)n; heap_used("malloc"); return NULL; }
void *__wrap_calloc(size_t n, size_t m) { (void)n; (void)m; heap_used("calloc"); return NULL; }
void *__wrap_realloc(void *p, size_t n) { (void)p; (void)n; heap_used("realloc"); return NULL; }
void __wrap_free(void *p) { (void)p; heap_used("free"); }
void *__wrap_aligned_alloc(size_t a, size_t n) { (void)a; (void)n; heap_used("aligned_alloc"); return NULL; }
int __wrap_posix_memalign(void **p, size_t a, size_t n) { (void)p; (void)a; (void)n; heap_used("posix_memalign"); return 12; }
