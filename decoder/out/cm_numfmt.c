/*
 * cm_numfmt.c - integers and float32 values as decimal text, no stdio.
 *
 * Float algorithm (cm_fmt_f32), for a finite nonzero float f, a = |f|:
 *
 *  1. Decimal exponent e with 10^e <= a < 10^(e+1): estimated by dividing
 *     or multiplying a copy of a by 10 in a loop (at most 46 steps for the
 *     float range 1.4e-45 .. 3.4e38).  The estimate may be one off next to
 *     a power of ten; step 2 corrects it.
 *  2. s = a * 10^(8-e), a scaled into [1e8, 1e9), computed with at most
 *     three correctly rounded double operations: 10^k for k <= 22 is an
 *     exact double (built by k exact multiplications by 10), larger factors
 *     are applied in steps of 1e22 (also exact).  So the relative error of
 *     s is below 3 * 2^-53 < 3.4e-16, i.e. below 3.4e-7 (units of the 9th
 *     digit).  If s falls outside [1e8, 1e9), e moves by one and s is
 *     computed again.
 *  3. N = s rounded to the nearest integer.  When s is within 1e-6 of a
 *     half-integer (the error of step 2 could put it on the wrong side; this
 *     includes exact ties such as 1000000.125), the side is decided
 *     exactly: a = m * 2^q (m the 24-bit significand) is compared with the
 *     midpoint (fl + 1/2) * 10^(e-8) in integers, m * 5^k * 2^(q+1+k)
 *     against (2 fl + 1) (k = 8 - e; for k < 0 the power of five moves to
 *     the right side), with 256-bit integers; a tie goes to the even N.
 *     N = 1e9 (a rounded up to the next power of ten) becomes 1e8, e + 1.
 *  4. The text is N's nine digits with trailing zeros dropped, laid out as
 *     C's "%.9g" does (exponent form when e < -4 or e > 8).
 *
 * So the digits are the correctly rounded ones: byte for byte glibc's
 * "%.9g" (the unit test compares them; an exhaustive run over all 2^32
 * float bit patterns agreed).
 *
 * Why 9 correctly rounded digits read back as f: the printed value
 * D = N * 10^(e-8) is within 0.5 * 10^(e-8) <= 0.5e-8 * a of a (because
 * 10^e <= a).  The floats next to a are at least a * 2^-24 away from it (a
 * normal float has a 24-bit significand; at a power of two the gap below
 * is the smaller one, a * 2^-24; subnormals have the fixed gap 2^-149,
 * relatively larger still), so every real within a * 2^-25 (~2.98e-8 * a)
 * of a rounds to f.  D is six times closer than that, so a correctly
 * rounding strtof returns f, and so does strtod followed by a cast to float
 * (the double nearest D is within 1.2e-16 * a of D, far inside the margin),
 * which is how most JSON and OBJ readers parse numbers.  Even without the
 * exact step 3 (digits off by one unit in a near-tie) the margin would hold.
 *
 * All arithmetic is IEEE binary64 + - * / and integer operations (no FMA:
 * the build uses -ffp-contract=off), so every architecture prints the same
 * text.
 */
#include "cm/cm_numfmt.h"

#include <math.h>
#include <string.h>

size_t cm_fmt_u64(char out[CM_FMT_U64_MAX], uint64_t v)
{
    char rev[CM_FMT_U64_MAX];
    size_t n = 0;
    do {
        rev[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0 && n < CM_FMT_U64_MAX - 1);
    for (size_t i = 0; i < n; i++)
        out[i] = rev[n - 1 - i];
    out[n] = '\0';
    return n;
}

/* 10^k, exact for 0 <= k <= 22: 10^22 = 2^22 * 5^22 and 5^22 < 2^53, so every partial product is a double */
static double pow10_exact(int k)
{
    double p = 1.0;
    for (int i = 0; i < k && i < 22; i++)
        p *= 10.0;
    return p;
}

/* ---- exact comparison for near-ties (step 3): small fixed-size unsigned integers ---- */
#define BN_LIMBS 8 /* 256 bits; the largest operand needs about 165 */
typedef struct bn {
    uint32_t w[BN_LIMBS]; /* least significant limb first */
} bn;

static void bn_set(bn *b, uint32_t v)
{
    memset(b, 0, sizeof *b);
    b->w[0] = v;
}

static void bn_mul_small(bn *b, uint32_t f)
{
    uint64_t c = 0;
    for (int i = 0; i < BN_LIMBS; i++) {
        c += (uint64_t)b->w[i] * f;
        b->w[i] = (uint32_t)c;
        c >>= 32;
    }
}

/* b *= 5^k (k <= 64) */
static void bn_mul_pow5(bn *b, int k)
{
    for (int i = 0; i < k && i < 64; i++)
        bn_mul_small(b, 5u);
}

/* b <<= s (0 <= s < 32 * BN_LIMBS; the callers' operands leave the top limbs free) */
static void bn_shl(bn *b, int s)
{
    int ls = s / 32, bs = s % 32;
    for (int i = BN_LIMBS - 1; i >= 0; i--) {
        uint32_t hi = i - ls >= 0 ? b->w[i - ls] : 0u;
        uint32_t lo = i - ls - 1 >= 0 ? b->w[i - ls - 1] : 0u;
        b->w[i] = bs != 0 ? (hi << bs) | (lo >> (32 - bs)) : hi;
    }
}

static int bn_cmp(const bn *a, const bn *b)
{
    for (int i = BN_LIMBS - 1; i >= 0; i--)
        if (a->w[i] != b->w[i])
            return a->w[i] > b->w[i] ? 1 : -1;
    return 0;
}

/*
 * Sign of m * 2^q - (2 fl + 1)/2 * 10^-k, exactly (fl < 1e9; k in [-32, 56];
 * m < 2^24, q in [-149, 104]).  Multiplying by 2 * 10^k and splitting
 * 10^k = 5^k * 2^k: compare m * 5^k * 2^(q+1+k) with (2 fl + 1), the power
 * of five going to the right side when k < 0.
 */
static int cmp_midpoint(uint32_t m, int q, int k, uint32_t fl)
{
    bn A, B;
    bn_set(&A, m);
    bn_set(&B, 2u * fl + 1u);
    if (k >= 0)
        bn_mul_pow5(&A, k);
    else
        bn_mul_pow5(&B, -k);
    int x = q + 1 + k;
    if (x >= 0)
        bn_shl(&A, x < 32 * BN_LIMBS ? x : 32 * BN_LIMBS - 1);
    else
        bn_shl(&B, -x < 32 * BN_LIMBS ? -x : 32 * BN_LIMBS - 1);
    return bn_cmp(&A, &B);
}

/* a * 10^k with at most three roundings (k in [-32, 56] for float inputs) */
static double scale10(double a, int k)
{
    double s = a;
    if (k >= 0) {
        for (int i = 0; i < 3 && k > 22; i++) {
            s *= 1e22;
            k -= 22;
        }
        return s * pow10_exact(k);
    }
    k = -k;
    for (int i = 0; i < 3 && k > 22; i++) {
        s /= 1e22;
        k -= 22;
    }
    return s / pow10_exact(k);
}

size_t cm_fmt_f32(char out[CM_FMT_F32_MAX], float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    size_t n = 0;
    if ((bits & 0x7F800000u) == 0x7F800000u) { /* inf or NaN */
        out[0] = '\0';
        return 0;
    }
    if (bits >> 31)
        out[n++] = '-';
    if ((bits & 0x7FFFFFFFu) == 0) {
        out[n++] = '0';
        out[n] = '\0';
        return n;
    }
    double a = fabs((double)f);

    /* 1. estimate of the decimal exponent */
    int e = 0;
    double t = a;
    for (int i = 0; i < 64 && t >= 10.0; i++) {
        t /= 10.0;
        e++;
    }
    for (int i = 0; i < 64 && t < 1.0; i++) {
        t *= 10.0;
        e--;
    }
    /* 2. nine digits' worth of a, one correction of the estimate */
    double s = scale10(a, 8 - e);
    if (s >= 1e9) {
        e++;
        s = scale10(a, 8 - e);
    } else if (s < 1e8) {
        e--;
        s = scale10(a, 8 - e);
    }
    /* 3. round to an integer; near a half-integer decide exactly, ties to even */
    double fl = floor(s);
    double frac = s - fl; /* exact: s < 2^31 */
    uint32_t N = (uint32_t)fl; /* fl < 1e9 + 1: 32 bits (no 64-bit conversion helper on armhf) */
    if (frac > 0.5 - 1e-6 && frac < 0.5 + 1e-6) {
        uint32_t ex = (bits >> 23) & 0xFFu;
        uint32_t m = ex != 0 ? (bits & 0x7FFFFFu) | 0x800000u : bits & 0x7FFFFFu;
        int q = ex != 0 ? (int)ex - 150 : -149;
        int c = cmp_midpoint(m, q, 8 - e, N);
        if (c > 0 || (c == 0 && (N & 1u)))
            N++;
    } else if (frac > 0.5) {
        N++;
    }
    if (N >= 1000000000u) { /* rounded up to a power of ten (or s hit 1e9 at the boundary) */
        N = (N + 5u) / 10u;
        e++;
    } else if (N < 100000000u) { /* cannot happen after step 2; keeps nine digits regardless */
        N *= 10u;
        e--;
    }

    char dg[9];
    for (int i = 8; i >= 0; i--) {
        dg[i] = (char)('0' + (int)(N % 10u));
        N /= 10u;
    }
    int nd = 9;
    while (nd > 1 && dg[nd - 1] == '0')
        nd--;

    if (e < -4 || e >= 9) { /* d[.ddd]e±XX */
        out[n++] = dg[0];
        if (nd > 1) {
            out[n++] = '.';
            for (int i = 1; i < nd; i++)
                out[n++] = dg[i];
        }
        out[n++] = 'e';
        out[n++] = e < 0 ? '-' : '+';
        int x = e < 0 ? -e : e; /* 4 < x <= 45 for floats: two digits */
        out[n++] = (char)('0' + x / 10);
        out[n++] = (char)('0' + x % 10);
    } else if (e >= 0) { /* ddd[.ddd] */
        for (int i = 0; i <= e; i++)
            out[n++] = i < nd ? dg[i] : '0';
        if (nd > e + 1) {
            out[n++] = '.';
            for (int i = e + 1; i < nd; i++)
                out[n++] = dg[i];
        }
    } else { /* 0.000ddd */
        out[n++] = '0';
        out[n++] = '.';
        for (int i = 0; i < -e - 1; i++)
            out[n++] = '0';
        for (int i = 0; i < nd; i++)
            out[n++] = dg[i];
    }
    out[n] = '\0';
    return n;
}
