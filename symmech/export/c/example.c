/* Example program of an exported symmech model: runs the scene from its start values (DOP853, or Radau IIA
   with dense output for a stiff model) and prints the native run's main table (TABLE_HEADER, one row per
   output time) as CSV. Hand-written; the physics is the generated module. Build with `make`, run
   `./example`. */
#include <float.h>
#include <math.h>
#include <stdio.h>

#include "symmech_model.h"

/* the model's notices (a rocking contact, the stop at max_impacts) on stderr */
static void notice(void *env, double t, const char *message)
{
    (void)env;
    fprintf(stderr, "%s: t = %.17g s: %s\n", MODEL_IDENTIFIER, t, message);
}

/* N = x 10^k rounded to the nearest integer, ties to even (printf's rounding), for x >= 0 and k in [0, 22]
   (10^k exact in a double); *range -1 where x 10^k < 10^16, 1 where it is >= 10^17, else 0. Exact: hi =
   fl(x 10^k) and lo = fma(x, 10^k, -hi) sum to x 10^k exactly (fma rounds once), and at range 0 hi >= 10^16 >
   2^53 is an integer, so N is hi + n or hi + n + 1 with n = floor(lo), decided by comparing lo with the exact
   n + 0.5; 10^16 and 10^17 are exact doubles, so the range follows from hi and lo's sign. */
static long long scaled(double x, int k, int *range)
{
    static const double ten[23] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13,
                                   1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    double hi = x * ten[k], lo = fma(x, ten[k], -hi), n = floor(lo);
    *range = hi < 1e16 || (hi == 1e16 && lo < 0.0) ? -1 : hi > 1e17 || (hi == 1e17 && lo >= 0.0);
    if (*range != 0) return 0;
    long long base = (long long)hi + (long long)n;
    return base + (lo > n + 0.5 || (lo == n + 0.5 && base % 2 != 0));
}

/* the 17 digits of a number's magnitude and its exponent e in [-6, 16] into s as %g writes them: trailing zeros
   dropped, fixed notation from e = -4, d.ddde-0X below */
static void write_g(char *s, const char *digits, int e, int negative)
{
    int last = 16;  /* the last digit kept */
    while (last > 0 && digits[last] == '0') last--;
    if (negative) *s++ = '-';
    if (e < -4) {
        *s++ = digits[0];
        if (last > 0) *s++ = '.';
        for (int i = 1; i <= last; i++) *s++ = digits[i];
        *s++ = 'e';
        *s++ = '-';
        *s++ = '0';
        *s++ = (char)('0' - e);
        *s = '\0';
        return;
    }
    if (e < 0) {  /* 0.000ddd */
        *s++ = '0';
        *s++ = '.';
        for (int i = -1; i > e; i--) *s++ = '0';
    }
    for (int i = 0; i <= (last > e ? last : e); i++) {
        if (i == e + 1 && e >= 0) *s++ = '.';
        *s++ = digits[i];
    }
    *s = '\0';
}

/* x as printf's "%.17g" writes it (17 significant digits, correctly rounded: read back, the same double), into
   s (>= 32 chars). For |x| in [1e-6, 1e16) the digits are N = round(|x| 10^k) with |x| 10^k in [10^16, 10^17)
   (scaled: exact integer arithmetic instead of printf's multi-precision, most of the example's printing time),
   the exponent 16 - k in [-6, 15] (one more where N rounds up to 10^17); elsewhere (0, tiny, large, not finite)
   snprintf. */
static void format_g17(double x, char *s)
{
    double ax = fabs(x);
    /* the proof needs each product rounded to a double: where expressions are evaluated wider (x87), printf */
    int k = FLT_EVAL_METHOD == 0 && ax >= 1e-6 && ax < 1e16 ? 16 - (int)floor(log10(ax)) : -1, range = 1;
    long long n = 0;
    while (k >= 1 && k <= 22) {  /* log10's estimate corrected: below 10^16 at k, below 10^17 at k + 1 */
        n = scaled(ax, k, &range);
        if (range == 0) break;
        k += range < 0 ? 1 : -1;
    }
    if (range != 0) {
        snprintf(s, 32, "%.17g", x);
        return;
    }
    int e = 16 - k;
    if (n == 100000000000000000LL) {  /* rounded up to the next power of ten */
        n /= 10;
        e++;
    }
    char digits[17];
    for (int i = 16; i >= 0; i--, n /= 10) digits[i] = (char)('0' + n % 10);
    write_g(s, digits, e, x < 0);
}

int main(void)
{
    static const int columns[] = TABLE_VRS;
    static SymmechModel model;  /* zeroed: no notice environment */
    symmech_reset(&model);
    model.notice = notice;
    model.horizon = TABLE_STOP;  /* no inputs change on the way: steps need not stop at the printed times */
    if (symmech_start(&model) != 0) {
        fprintf(stderr, "%s: singular mass matrix or non-finite rates at the start\n", MODEL_IDENTIFIER);
        return 1;
    }
    printf("%s\n", TABLE_HEADER);
    for (int k = 0; k <= TABLE_STEPS; k++) {
        double t = k == TABLE_STEPS ? TABLE_STOP : TABLE_STOP / TABLE_STEPS * k;
        int status = symmech_integrate(&model, t, EXAMPLE_RTOL, EXAMPLE_ATOL);
        if (status == 1) return 0;  /* the model ended the run (its notice printed) */
        if (status != 0) {
            fprintf(stderr, "%s: the integration failed at t = %g s\n", MODEL_IDENTIFIER, t);
            return 1;
        }
        char text[32];
        format_g17(t, text);
        fputs(text, stdout);
        for (size_t i = 0; i < sizeof columns / sizeof columns[0]; i++) {
            format_g17(model.r[columns[i]], text);
            putchar(',');
            fputs(text, stdout);
        }
        putchar('\n');
    }
    return 0;
}
