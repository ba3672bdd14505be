/* Generic numerics of an exported symmech model: the linear solve of M y' = F (LU with partial pivoting, or
   Cholesky where the model declares its block of M symmetric positive definite: MASS_SPD), Dormand and Prince's
   DOP853 with the error control of Hairer's dop853.f and its dense output of order 7 (the tableau in
   dop853_tableau.h is written from symmech/numerics/dop853.py), state events located on that dense output by the
   Illinois method (golden section finding the grazing dips between its samples) and, for a stiff model
   (MODEL_STIFF), Radau IIA of order 5 as scipy's and symmech/numerics/radau.py's (radau_tableau.h written from
   symmech/numerics/radau_tableau.py) with dense output. Hand-written; the physics is generated. */
#include <math.h>
#include <string.h>

#include "symmech_model.h"
#include "dop853_tableau.h"
#ifdef MODEL_STIFF
#include "radau_tableau.h"
#endif

/* before the short loops of the linear solves, whose sizes are compile-time constants: unrolled (whole up to 16
   trips; GCC keeps them rolled at -O2, where the counting and branching cost as much as the arithmetic), the same
   operations in the same order, so the same results */
#if defined(__clang__)
#define UNROLLED _Pragma("unroll 16")
#elif defined(__GNUC__)
#define UNROLLED _Pragma("GCC unroll 16")
#else
#define UNROLLED
#endif

void symmech_reset(SymmechModel *m)
{
    static const double start[N_REAL] = START_VALUES;
    memcpy(m->r, start, sizeof start);
    m->dirty = 1;
    m->horizon = 0.0;
#ifdef MODEL_STIFF
    m->radau.h = 0.0;  /* no solve to resume */
#endif
}

#if defined(MODEL_STIFF) || ((defined(MODEL_RATE_MASS) || defined(MODEL_RATE_AND_MASS_BLOCK)) && !defined(MASS_SPD))
/* LU factors of a (n x n row-major) with partial pivoting, in place, row swaps into piv; 0, or -1 when
   singular */
static int lu_factor(double *a, int *piv, int n)
{
    for (int k = 0; k < n; k++) {
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[pivot * n + k])) pivot = i;
        piv[k] = pivot;
        if (a[pivot * n + k] == 0.0) return -1;
        if (pivot != k)
            for (int j = 0; j < n; j++) {
                double s = a[k * n + j]; a[k * n + j] = a[pivot * n + j]; a[pivot * n + j] = s;
            }
        for (int i = k + 1; i < n; i++) {
            double f = a[i * n + k] /= a[k * n + k];
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; j++) a[i * n + j] -= f * a[k * n + j];
        }
    }
    return 0;
}

/* b = a^-1 b in place from the factors of lu_factor */
static void lu_solve(const double *a, const int *piv, double *b, int n)
{
    for (int k = 0; k < n; k++) {
        double s = b[k]; b[k] = b[piv[k]]; b[piv[k]] = s;
    }
    UNROLLED
    for (int i = 0; i < n; i++)
        UNROLLED
        for (int j = 0; j < i; j++) b[i] -= a[i * n + j] * b[j];
    UNROLLED
    for (int i = n - 1; i >= 0; i--) {
        UNROLLED
        for (int j = i + 1; j < n; j++) b[i] -= a[i * n + j] * b[j];
        b[i] /= a[i * n + i];
    }
}
#endif

#if defined(MODEL_RATE_MASS) || defined(MODEL_RATE_AND_MASS_BLOCK)
#define N_M (N_X - MASS_IDENTITY)
#ifdef MODEL_RATE_AND_MASS_BLOCK  /* the model writes M22 alone, row by row */
#define MASS_STRIDE N_M
#define MASS_AT 0
#else  /* the model writes M whole: M22 from row and column MASS_IDENTITY */
#define MASS_STRIDE N_X
#define MASS_AT (MASS_IDENTITY * N_X + MASS_IDENTITY)
#endif

#ifdef MASS_SPD
/* b = M22^-1 b (N_M) by Cholesky, M22 the symmetric positive definite block of M (at mass + MASS_AT, row stride
   MASS_STRIDE; its lower triangle read and overwritten by the factor); 0, or -1 when it is not positive
   definite. Half the work of LU and no pivot search; the sizes are compile-time constants. */
static int solve_mass(double *mass, double *b)
{
    double *a = mass + MASS_AT, inv[N_M];
    UNROLLED
    for (int j = 0; j < N_M; j++) {
        double d = a[j * MASS_STRIDE + j];
        UNROLLED
        for (int k = 0; k < j; k++) d -= a[j * MASS_STRIDE + k] * a[j * MASS_STRIDE + k];
        if (!(d > 0.0)) return -1;
        inv[j] = 1.0 / sqrt(d);
        UNROLLED
        for (int i = j + 1; i < N_M; i++) {
            double s = a[i * MASS_STRIDE + j];
            UNROLLED
            for (int k = 0; k < j; k++) s -= a[i * MASS_STRIDE + k] * a[j * MASS_STRIDE + k];
            a[i * MASS_STRIDE + j] = s * inv[j];
        }
    }
    UNROLLED
    for (int i = 0; i < N_M; i++) {  /* L z = b, then L^T x = z */
        double s = b[i];
        UNROLLED
        for (int k = 0; k < i; k++) s -= a[i * MASS_STRIDE + k] * b[k];
        b[i] = s * inv[i];
    }
    UNROLLED
    for (int i = N_M - 1; i >= 0; i--) {
        double s = b[i];
        UNROLLED
        for (int k = i + 1; k < N_M; k++) s -= a[k * MASS_STRIDE + i] * b[k];
        b[i] = s * inv[i];
    }
    return 0;
}
#else
/* b = M22^-1 b (N_M) by LU with partial pivoting, M22 packed row by row at the start of mass (never overwriting
   a row still to read) and overwritten by its factors; 0, or -1 when singular */
static int solve_mass(double *mass, double *b)
{
    int piv[N_M];
    for (int i = 0; MASS_STRIDE != N_M && i < N_M; i++)
        for (int j = 0; j < N_M; j++) mass[i * N_M + j] = mass[MASS_AT + i * MASS_STRIDE + j];
    if (lu_factor(mass, piv, N_M) != 0) return -1;
    lu_solve(mass, piv, b, N_M);
    return 0;
}
#endif
#endif

/* y' at (t, y) with the instance's inputs and parameters; M = diag(I, M22) with an identity block of
   MASS_IDENTITY rows: only M22 is factored */
static int rates(SymmechModel *m, double t, const double *y, double *out)
{
    const double *p = m->r + VR_P;
#ifdef MODEL_RATE_AND_MASS_BLOCK
    MODEL_RATE_AND_MASS_BLOCK(t, y, p, out, m->mass);
#else
    MODEL_RATE(t, y, p, out);
#endif
    for (int k = 0; k < N_U; k++) out[U_ROW + k] += m->r[VR_U + k];
#if defined(MODEL_RATE_AND_MASS_BLOCK)
    return solve_mass(m->mass, out + MASS_IDENTITY);
#elif defined(MODEL_RATE_MASS)
    MODEL_RATE_MASS(t, y, p, m->mass);
    return solve_mass(m->mass, out + MASS_IDENTITY);
#else
    (void)m;  /* M is the identity */
    return 0;
#endif
}

int symmech_derivatives(SymmechModel *m)
{
    if (!m->dirty) return 0;
    if (rates(m, m->r[VR_TIME], m->r + VR_X, m->dx) != 0) return -1;
    for (int k = 0; k < N_X; k++)
        if (!isfinite(m->dx[k])) return -1;
    for (int k = 0; k < N_DX; k++) m->r[VR_DX + k] = m->dx[DX_FIRST + k];
#ifdef MODEL_OUTPUTS
    MODEL_OUTPUTS(m->r[VR_TIME], m->r + VR_X, m->dx, m->r + VR_P, m->r + VR_Y);
#endif
#if N_Z > 0
    MODEL_EVENTS(m->r[VR_TIME], m->r + VR_X, m->r + VR_P, m->r + VR_Z);
#endif
    m->dirty = 0;
    return 0;
}

#if defined(MODEL_STIFF) && N_Z > 0
#error "state events are located by DOP853 only: a stiff model has none"
#endif

int symmech_event_update(SymmechModel *m)
{
#if N_Z > 0
    if (symmech_derivatives(m) != 0) return -1;
    int changed = MODEL_EVENT_UPDATE(m->r[VR_TIME], m->r + VR_X, m->r + VR_P);
    const char *notice = MODEL_NOTICE(m->r + VR_P);
    if (notice != NULL && m->notice != NULL) m->notice(m->notice_env, m->r[VR_TIME], notice);
    if (changed <= 0 || changed == SYMMECH_STOP) return changed;
    for (int j = 0; j < N_X; j++)
        if (!isfinite(m->r[VR_X + j])) return -1;
    m->dirty = 1;
    return symmech_derivatives(m) != 0 ? -1 : 1;
#else
    (void)m;
    return 0;
#endif
}

int symmech_start(SymmechModel *m)
{
    if (symmech_derivatives(m) != 0) return -1;
    return symmech_event_update(m) < 0 ? -1 : 0;
}

int symmech_left_model(SymmechModel *m)
{
#if N_Z > 0
    if (symmech_derivatives(m) != 0) return 0;
    for (int i = 0; i < N_Z; i++)
        if (m->r[VR_Z + i] < -EVENT_TOLERANCE) return 1;
#endif
    (void)m;
    return 0;
}

#ifndef MODEL_STIFF
/* stage s of a DOP853 step of size h from (t, y), the stages before it in k: k[s] */
static int stage(SymmechModel *m, double t, const double *y, double h, double k[][N_X], int s)
{
    double z[N_X];
    for (int i = 0; i < N_X; i++) {
        double sum = 0.0;
        for (int j = 0; j < s; j++) sum += DOP853_A[s][j] * k[j][i];
        z[i] = y[i] + h * sum;
    }
    return rates(m, t + DOP853_C[s] * h, z, k[s]);
}

/* one DOP853 step of size h from (t, y) whose first stage k[0] is set: the stages k[1..], y1 = y(t + h) */
static int dop853_step(SymmechModel *m, double t, const double *y, double h, double k[][N_X], double *y1)
{
    for (int s = 1; s < DOP853_STAGES; s++)
        if (stage(m, t, y, h, k, s) != 0) return -1;
    for (int i = 0; i < N_X; i++) {
        double sum = 0.0;
        for (int j = 0; j < DOP853_STAGES; j++) sum += DOP853_B[j] * k[j][i];
        y1[i] = y[i] + h * sum;
    }
    return 0;
}

#if N_Z > 0
/* one accepted DOP853 step as its interpolant of order 7: from (t, y) of length h, the coefficients F row by row */
typedef struct {
    double t, h, y[N_X];
    double F[DOP853_POWER][N_X];
} Dense;

/* The accepted step h from (t, y) to y1 (stages k[0..DOP853_STAGES], the last f at y1) as its interpolant
   (scipy's DOP853._dense_output_impl): the 3 extra stages into k, the step into s */
static int dop853_dense(SymmechModel *m, double t, const double *y, const double *y1, double h, double k[][N_X],
                        Dense *s)
{
    for (int st = DOP853_STAGES + 1; st < DOP853_EXTENDED; st++)
        if (stage(m, t, y, h, k, st) != 0) return -1;
    s->t = t;
    s->h = h;
    memcpy(s->y, y, sizeof s->y);
    for (int i = 0; i < N_X; i++) {
        double dy = y1[i] - y[i];
        s->F[0][i] = dy;
        s->F[1][i] = h * k[0][i] - dy;
        s->F[2][i] = 2.0 * dy - h * (k[DOP853_STAGES][i] + k[0][i]);
        for (int r = 0; r < DOP853_POWER - 3; r++) {
            double sum = 0.0;
            for (int j = 0; j < DOP853_EXTENDED; j++) sum += DOP853_D[r][j] * k[j][i];
            s->F[3 + r][i] = h * sum;
        }
    }
    return 0;
}

/* the interpolant at the fraction x of the step: y at its start plus the nested form in x and 1 - x */
static void dense_at(const Dense *s, double x, double *out)
{
    for (int i = 0; i < N_X; i++) {
        double acc = 0.0;
        for (int r = 0; r < DOP853_POWER; r++) {
            acc += s->F[DOP853_POWER - 1 - r][i];
            acc *= r % 2 == 0 ? x : 1.0 - x;
        }
        out[i] = s->y[i] + acc;
    }
}

/* indicator i at the fraction x of the step s */
static double indicator_at(SymmechModel *m, const Dense *s, double x, int i)
{
    double z[N_Z], yx[N_X];
    dense_at(s, x, yx);
    MODEL_EVENTS(s->t + x * s->h, yx, m->r + VR_P, z);
    return z[i];
}

/* a bracket [lo, hi] of fractions of the step s still wider than 4 ulp of t */
static int wide(const Dense *s, double lo, double hi)
{
    return (hi - lo) * s->h > 4 * 2.2e-16 * fmax(fabs(s->t), s->h);
}

/* Indicator i's fall through zero between the fractions lo (where it is f_lo > 0) and hi (f_hi <= 0) of the step,
   by the Illinois method on the interpolant, to 4 ulp of t: the fraction on the side where it is <= 0 */
static double fall_of(SymmechModel *m, const Dense *s, int i, double lo, double f_lo, double hi, double f_hi)
{
    int side = 0;
    for (int it = 0; it < 200 && wide(s, lo, hi); it++) {
        double x = hi - f_hi * (hi - lo) / (f_hi - f_lo);
        if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
        double f = indicator_at(m, s, x, i);
        if (f > 0.0) {
            lo = x; f_lo = f;
            if (side == -1) f_hi *= 0.5;
            side = -1;
        } else {
            hi = x; f_hi = f;
            if (side == 1) f_lo *= 0.5;
            side = 1;
        }
    }
    return hi;
}

/* Golden section on the interpolant for the extremum of indicator i between the fractions lo and hi of the step,
   its maximum (sign 1: stopped at the first positive value) or its minimum (sign -1: stopped at the first value
   <= 0). That fraction and the value into *f, or -1 when none is found (to 4 ulp of t). */
static double golden(SymmechModel *m, const Dense *s, int i, double lo, double hi, int sign, double *f)
{
    const double golden = 0.6180339887498949;
    double a = hi - golden * (hi - lo), b = lo + golden * (hi - lo);
    double fa = indicator_at(m, s, a, i), fb = indicator_at(m, s, b, i);
    while ((sign > 0 ? fa <= 0.0 && fb <= 0.0 : fa > 0.0 && fb > 0.0) && wide(s, lo, hi)) {
        if (sign * fa >= sign * fb) {
            hi = b; b = a; fb = fa;
            a = hi - golden * (hi - lo);
            fa = indicator_at(m, s, a, i);
        } else {
            lo = a; a = b; fa = fb;
            b = lo + golden * (hi - lo);
            fb = indicator_at(m, s, b, i);
        }
    }
    if (sign > 0 ? fa > 0.0 : fa <= 0.0) { *f = fa; return a; }
    if (sign > 0 ? fb > 0.0 : fb <= 0.0) { *f = fb; return b; }
    return -1.0;
}

/* A grazing fall of indicator i, positive at the fraction lo (f_lo): where it dips to <= 0 between lo and hi and
   rises back (the native engine's scan: a local minimum among its samples, minimised there), the fall located
   before the dip's bottom; 2 when it stays positive */
static double dip_of(SymmechModel *m, const Dense *s, int i, double lo, double f_lo, double hi)
{
    double f;
    double x = golden(m, s, i, lo, hi, -1, &f);
    return x < 0.0 ? 2.0 : fall_of(m, s, i, lo, f_lo, x, f);
}

/* samples of the scan per step; the fraction of the previous step's last sample but one */
#define SCAN_POINTS 8
#define BEFORE_LAST ((double)(SCAN_POINTS - 1) / SCAN_POINTS)
/* where an indicator's slope at a step's start or end is read, as a fraction of the step */
#define PROBE 1e-6

/* The first event of indicator i in the samples z[0..j] (z[j][i] the newest at the fraction x) of the step s,
   found when z[j] is sampled: a fall bracketed between z[j - 1] and z[j] (positive, then non-positive; or both
   non-positive and lower at z[j], with a positive value between them: a short flight after a bounce), or a
   grazing dip around z[j - 1] where it is a positive local minimum (z[-1] = z_before, the previous step's sample at
   BEFORE_LAST; without one NAN, the indicator's slope at the start deciding, or -INFINITY, none searched); 2 when
   none */
static double event_of(SymmechModel *m, const Dense *s, int i, const double z[][N_Z], int j, double z_before)
{
    double lo = (double)(j - 1) / SCAN_POINTS, x = (double)j / SCAN_POINTS, f_lo = z[j - 1][i], f_up;
    if (z[j][i] <= 0.0) {
        if (f_lo > 0.0) return fall_of(m, s, i, lo, f_lo, x, z[j][i]);
        double up = z[j][i] < f_lo ? golden(m, s, i, lo, x, 1, &f_up) : -1.0;
        return up < 0.0 ? 2.0 : fall_of(m, s, i, up, f_up, x, z[j][i]);
    }
    double left = j >= 2 ? z[j - 2][i] : z_before;
    if (!(f_lo > 0.0 && f_lo <= z[j][i])) return 2.0;
    if (j >= 2) return f_lo < left ? dip_of(m, s, i, (double)(j - 2) / SCAN_POINTS, left, x) : 2.0;
    /* at the step's start: falling into it from the previous step, or (no previous sample) falling at its start */
    if (isnan(left) ? indicator_at(m, s, PROBE, i) < f_lo : f_lo < left)
        return dip_of(m, s, i, 0.0, f_lo, x);
    return 2.0;
}

/* The first event within the accepted step s (z0: the indicators at its start, y1 its end): the interpolant
   sampled at SCAN_POINTS fractions, each indicator's first event (event_of), the earliest of them; where the
   step is the integration's last (end_of_run), a grazing dip after its last sample but one where the indicator
   falls into the end. A grazing dip that straddles the start of s and lies in the previous step (prev, its
   sample z_before at BEFORE_LAST; NULL, none) is located there: *where is then prev. The fraction of the step
   (in (0, 1]) and the state there into y_event; 0 when nothing falls; z_last: the sample at BEFORE_LAST; no_prev:
   event_of's z_before without a previous step. */
static double first_fall(SymmechModel *m, const Dense *s, const Dense *prev, const double *z_before,
                         double no_prev, const double *z0, const double *y1, int end_of_run, double *y_event,
                         const Dense **where, double *z_last)
{
    double z[SCAN_POINTS + 1][N_Z], yx[N_X];
    memcpy(z[0], z0, sizeof z[0]);
    *where = s;
    for (int j = 1; j <= SCAN_POINTS; j++) {
        double x = (double)j / SCAN_POINTS, first = 2.0;
        if (j < SCAN_POINTS) dense_at(s, x, yx);
        else memcpy(yx, y1, sizeof yx);
        MODEL_EVENTS(s->t + x * s->h, yx, m->r + VR_P, z[j]);
        for (int i = 0; j == 1 && prev != NULL && i < N_Z; i++) {  /* a minimum at the start of s: its earlier side */
            if (!(z0[i] > 0.0 && z0[i] < z_before[i] && z0[i] <= z[1][i])) continue;
            double x_prev = dip_of(m, prev, i, BEFORE_LAST, z_before[i], 1.0);
            if (x_prev <= 1.0) {
                dense_at(prev, x_prev, y_event);
                *where = prev;
                return x_prev;
            }
        }
        for (int i = 0; i < N_Z; i++) {
            first = fmin(first, event_of(m, s, i, (const double (*)[N_Z])z, j, prev ? z_before[i] : no_prev));
            if (end_of_run && j == SCAN_POINTS && z[j][i] > 0.0 && z[j][i] < z[j - 1][i]
                && indicator_at(m, s, 1.0 - PROBE, i) <= z[j][i])  /* a minimum before the end, none after it */
                first = fmin(first, dip_of(m, s, i, BEFORE_LAST, z[j - 1][i], 1.0));
        }
        if (first <= 1.0) {
            if (first < 1.0) dense_at(s, first, y_event);
            else memcpy(y_event, y1, sizeof yx);
            return first;
        }
    }
    memcpy(z_last, z[SCAN_POINTS - 1], sizeof z[0]);
    return 0.0;
}

/* The event search of one dop853 call: the last two accepted steps without an event between them (a dip at their
   boundary is searched on both), the indicators at the current step's start and at the previous step's sample
   BEFORE_LAST */
typedef struct {
    Dense steps[2];
    int current;   /* steps[current]: the step searched next */
    int has_prev;  /* steps[1 - current] precedes it */
    double no_prev;  /* else at a call's start NAN, after an event -INFINITY (its update settled the start: an
                        indicator there at its round-off is no dip) */
    double z0[N_Z], z_before[N_Z];
} Scan;

static void scan_start(SymmechModel *m, Scan *scan, double no_prev)
{
    scan->has_prev = 0;
    scan->no_prev = no_prev;
    MODEL_EVENTS(m->r[VR_TIME], m->r + VR_X, m->r + VR_P, scan->z0);
}

/* The accepted step h from (r[VR_TIME], r[VR_X]) to y1 (stages k, the last f at y1; end_of_run: the call's last)
   searched for an event (first_fall): where one falls, the time and the state set to it and the model's update
   applied, 1 (or SYMMECH_STOP, the model's); 0 when none (the step becomes the previous one); -1 on a failure */
static int step_events(SymmechModel *m, Scan *scan, const double *y1, double h, double k[][N_X], int end_of_run,
                       double t_end)
{
    Dense *s = &scan->steps[scan->current];
    const Dense *prev = scan->has_prev ? &scan->steps[1 - scan->current] : NULL, *where;
    double y_event[N_X], z_last[N_Z] = {0.0};
    if (dop853_dense(m, m->r[VR_TIME], m->r + VR_X, y1, h, k, s) != 0) return -1;
    double x = first_fall(m, s, prev, scan->z_before, scan->no_prev, scan->z0, y1, end_of_run, y_event, &where,
                          z_last);
    if (x <= 0.0) {
        memcpy(scan->z_before, z_last, sizeof z_last);
        scan->current = 1 - scan->current;
        scan->has_prev = 1;
        return 0;
    }
    m->r[VR_TIME] = x == 1.0 && where == s && end_of_run ? t_end : where->t + x * where->h;
    memcpy(m->r + VR_X, y_event, sizeof y_event);
    m->dirty = 1;
    int update = symmech_event_update(m);
    if (update >= 0) scan_start(m, scan, -INFINITY);
    return update == SYMMECH_STOP ? update : update < 0 ? -1 : 1;
}
#endif

/* DOP853 from r[VR_TIME] to t_end with Hairer's error control; with state events, each accepted step's
   interpolant searched for an indicator's fall (first_fall), the model's update applied there
   (symmech_event_update) and the integration resumed from it */
static int dop853(SymmechModel *m, double t_end, double rtol, double atol)
{
    double k[DOP853_EXTENDED][N_X], y1[N_X];
    double *y = m->r + VR_X;
    double t = m->r[VR_TIME];
    if (t_end <= t) return 0;
    if (rates(m, t, y, k[0]) != 0) return -1;
#if N_Z > 0
    Scan scan = {.current = 0};
    scan_start(m, &scan, NAN);
#endif
    double h = t_end - t, norm_y = 0.0, norm_f = 0.0;
    for (int i = 0; i < N_X; i++) {  /* Hairer's first guess: |y| / |f| scaled, at most the interval */
        double sc = atol + rtol * fabs(y[i]);
        norm_y += (y[i] / sc) * (y[i] / sc);
        norm_f += (k[0][i] / sc) * (k[0][i] / sc);
    }
    if (norm_y > 1e-10 && norm_f > 1e-10) h = fmin(h, 0.01 * sqrt(norm_y / norm_f));
    else h = fmin(h, 1e-6);
    while (t < t_end) {
        int last = t + h >= t_end;
        if (last) h = t_end - t;
        if (last && h <= 16 * 2.2e-16 * fabs(t)) break;  /* an event within round-off of t_end */
        if (h < 16 * 2.2e-16 * fabs(t) || h <= 0.0) return -1;
        if (dop853_step(m, t, y, h, k, y1) != 0) return -1;
        if (rates(m, t + h, y1, k[DOP853_STAGES]) != 0) return -1;
        double err5 = 0.0, err3 = 0.0;
        for (int i = 0; i < N_X; i++) {
            double e5 = 0.0, e3 = 0.0;
            for (int j = 0; j <= DOP853_STAGES; j++) { e5 += DOP853_E5[j] * k[j][i]; e3 += DOP853_E3[j] * k[j][i]; }
            double sc = atol + rtol * fmax(fabs(y[i]), fabs(y1[i]));
            err5 += (e5 / sc) * (e5 / sc);
            err3 += (e3 / sc) * (e3 / sc);
        }
        double denom = err5 + 0.01 * err3;
        double err = denom > 0.0 ? fabs(h) * err5 / sqrt(denom * N_X) : 0.0;
        if (!isfinite(err)) return -1;
        if (err > 1.0) {
            h *= fmax(0.2, 0.9 * pow(err, -1.0 / 8.0));
            continue;
        }
        double factor = err == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -1.0 / 8.0));
#if N_Z > 0
        m->r[VR_TIME] = t;
        int event = step_events(m, &scan, y1, h, k, last, t_end);
        if (event != 0) {  /* an event in the step: the update applied there, go on from it */
            if (event < 0) return -1;
            if (event == SYMMECH_STOP) return 1;
            t = m->r[VR_TIME];
            if (rates(m, t, y, k[0]) != 0) return -1;
            continue;
        }
#endif
        t = last ? t_end : t + h;
        memcpy(y, y1, sizeof y1);
        memcpy(k[0], k[DOP853_STAGES], sizeof k[0]);
#if N_Z > 0
        MODEL_EVENTS(t, y, m->r + VR_P, scan.z0);
        for (int i = 0; i < N_Z; i++)
            if (scan.z0[i] < -EVENT_TOLERANCE) { m->r[VR_TIME] = t; m->dirty = 1; return -2; }
#endif
        h *= factor;
    }
    m->r[VR_TIME] = t_end;
    m->dirty = 1;
    return symmech_derivatives(m);
}
#endif

#ifdef MODEL_STIFF
static const double NOMINAL[N_X] = NOMINALS;
#ifdef MODEL_SECOND_ORDER
#define N_H (N_X / 2)
#define N_LU N_H  /* the size of the factored systems */
#else
#define N_LU N_X
#endif

/* root mean square of x (n) scaled by atol * NOMINAL + rtol * |y| (scale n of them, repeated) */
static double scaled_rms(const double *x, int n, const double *scale)
{
    double acc = 0.0;
    for (int i = 0; i < n; i++) acc += (x[i] / scale[i % N_X]) * (x[i] / scale[i % N_X]);
    return sqrt(acc / n);
}

static void error_scale(const Radau *s, const double *y, const double *y_new, double *scale)
{
    for (int i = 0; i < N_X; i++)
        scale[i] = s->atol * NOMINAL[i] + s->rtol * fmax(fabs(y[i]), fabs(y_new[i]));
}

/* out (k x N_X) = a (k x 3) z (3 x N_X) */
static void mix(const double *a, int k, const double *z, double *out)
{
    for (int r = 0; r < k; r++)
        UNROLLED
        for (int i = 0; i < N_X; i++)
            out[r * N_X + i] = a[r * 3] * z[i] + a[r * 3 + 1] * z[N_X + i] + a[r * 3 + 2] * z[2 * N_X + i];
}

/* dy'/dy by forward differences of the rates (the steps scaled by the states' nominals) */
static int jacobian(SymmechModel *m, double t, const double *y, const double *f, double *J)
{
    double yj[N_X], fj[N_X];
    memcpy(yj, y, sizeof yj);
    for (int j = 0; j < N_X; j++) {
        double step = 1.4901161193847656e-08 * fmax(fabs(y[j]), NOMINAL[j]);
        yj[j] = y[j] + step;
        step = yj[j] - y[j];
        if (rates(m, t, yj, fj) != 0) return -1;
        for (int i = 0; i < N_X; i++) J[i * N_X + j] = (fj[i] - f[i]) / step;
        yj[j] = y[j];
    }
    return 0;
}

/* LU factors with partial pivoting (by |re| + |im|, as LAPACK's zgetrf) of the complex N_LU x N_LU matrix
   (re, im row-major) in place, row swaps into piv; 0, or -1 when singular. A quarter of the real 2 N_LU
   system's work to factor. */
static int lu_factor_complex(double *re, double *im, int *piv)
{
    for (int k = 0; k < N_LU; k++) {
        int pivot = k;
        for (int i = k + 1; i < N_LU; i++)
            if (fabs(re[i * N_LU + k]) + fabs(im[i * N_LU + k])
                > fabs(re[pivot * N_LU + k]) + fabs(im[pivot * N_LU + k])) pivot = i;
        piv[k] = pivot;
        if (re[pivot * N_LU + k] == 0.0 && im[pivot * N_LU + k] == 0.0) return -1;
        if (pivot != k)
            for (int j = 0; j < N_LU; j++) {
                double s = re[k * N_LU + j]; re[k * N_LU + j] = re[pivot * N_LU + j]; re[pivot * N_LU + j] = s;
                s = im[k * N_LU + j]; im[k * N_LU + j] = im[pivot * N_LU + j]; im[pivot * N_LU + j] = s;
            }
        double pr = re[k * N_LU + k], pi = im[k * N_LU + k], p2 = pr * pr + pi * pi;
        double ir = pr / p2, ii = -pi / p2;  /* 1 / pivot */
        for (int i = k + 1; i < N_LU; i++) {
            double ar = re[i * N_LU + k], ai = im[i * N_LU + k];
            double fr = ar * ir - ai * ii, fi = ar * ii + ai * ir;
            re[i * N_LU + k] = fr;
            im[i * N_LU + k] = fi;
            if (fr == 0.0 && fi == 0.0) continue;
            for (int j = k + 1; j < N_LU; j++) {
                double br = re[k * N_LU + j], bi = im[k * N_LU + j];
                re[i * N_LU + j] -= fr * br - fi * bi;
                im[i * N_LU + j] -= fr * bi + fi * br;
            }
        }
    }
    return 0;
}

/* (br, bi) = a^-1 (br, bi) in place from the factors of lu_factor_complex */
static void lu_solve_complex(const double *re, const double *im, const int *piv, double *br, double *bi)
{
    for (int k = 0; k < N_LU; k++) {
        double s = br[k]; br[k] = br[piv[k]]; br[piv[k]] = s;
        s = bi[k]; bi[k] = bi[piv[k]]; bi[piv[k]] = s;
    }
    UNROLLED
    for (int i = 0; i < N_LU; i++) {
        double sr = br[i], si = bi[i];
        UNROLLED
        for (int j = 0; j < i; j++) {
            sr -= re[i * N_LU + j] * br[j] - im[i * N_LU + j] * bi[j];
            si -= re[i * N_LU + j] * bi[j] + im[i * N_LU + j] * br[j];
        }
        br[i] = sr; bi[i] = si;
    }
    UNROLLED
    for (int i = N_LU - 1; i >= 0; i--) {
        double sr = br[i], si = bi[i];
        UNROLLED
        for (int j = i + 1; j < N_LU; j++) {
            sr -= re[i * N_LU + j] * br[j] - im[i * N_LU + j] * bi[j];
            si -= re[i * N_LU + j] * bi[j] + im[i * N_LU + j] * br[j];
        }
        double dr = re[i * N_LU + i], di = im[i * N_LU + i], d2 = dr * dr + di * di;
        br[i] = (sr * dr + si * di) / d2;
        bi[i] = (si * dr - sr * di) / d2;
    }
}

#ifdef MODEL_SECOND_ORDER
/* the Radau matrices a I - J of J = [[0, I], [J21, J22]] (the first N_H rates are y[N_H:], their rows of J
   exactly [0, I]), reduced to the N_H x N_H systems S(a) = a I - J22 - J21 / a of the second half (Hairer and
   Wanner's RADAU5 for second-order systems): an eighth of the factoring and half of each solve. The first half
   follows as x1 = (b1 + x2) / a: no cancellation at small steps (large a), where x2 = a x1 - b1 would have it. */
static void radau_matrices(Radau *s, double h)
{
    double ar = RADAU_MU_COMPLEX_RE / h, ai = RADAU_MU_COMPLEX_IM / h, a = RADAU_MU_REAL / h;
    double a2 = ar * ar + ai * ai, ir = ar / a2, ii = -ai / a2;  /* 1 / (ar + i ai) */
    for (int i = 0; i < N_H; i++)
        for (int j = 0; j < N_H; j++) {
            double j21 = s->J[(N_H + i) * N_X + j], j22 = s->J[(N_H + i) * N_X + N_H + j];
            s->lu_real[i * N_H + j] = (i == j ? a : 0.0) - j22 - j21 / a;
            s->lu_complex_re[i * N_H + j] = (i == j ? ar : 0.0) - j22 - j21 * ir;
            s->lu_complex_im[i * N_H + j] = (i == j ? ai : 0.0) - j21 * ii;
        }
}

/* b2 + J21 c into r (N_H): S(a) x2 = r solves (a I - J) x = (b1, b2) for x2 with c = b1 / a */
static void reduced(const Radau *s, const double *b, const double *c, double *r)
{
    for (int i = 0; i < N_H; i++) {
        double acc = b[N_H + i];
        UNROLLED
        for (int j = 0; j < N_H; j++) acc += s->J[(N_H + i) * N_X + j] * c[j];
        r[i] = acc;
    }
}
#else
/* the Radau matrices MU_REAL/h - J and MU_COMPLEX/h - J */
static void radau_matrices(Radau *s, double h)
{
    for (int i = 0; i < N_X * N_X; i++) {
        s->lu_real[i] = -s->J[i];
        s->lu_complex_re[i] = -s->J[i];
        s->lu_complex_im[i] = 0.0;
    }
    for (int i = 0; i < N_X; i++) {
        s->lu_real[i * N_X + i] += RADAU_MU_REAL / h;
        s->lu_complex_re[i * N_X + i] += RADAU_MU_COMPLEX_RE / h;
        s->lu_complex_im[i * N_X + i] = RADAU_MU_COMPLEX_IM / h;
    }
}
#endif

/* LU factors of the Radau matrices at step h (kept with them: their solves read it) */
static int factor(Radau *s, double h)
{
    radau_matrices(s, h);
    s->h_lu = h;
    if (lu_factor(s->lu_real, s->piv_real, N_LU) != 0
        || lu_factor_complex(s->lu_complex_re, s->lu_complex_im, s->piv_complex) != 0) return -1;
    s->lu_valid = 1;
    return 0;
}

/* b (N_X) = (MU_REAL/h - J)^-1 b, h that of the factors */
static void solve_real(const Radau *s, double *b)
{
#ifdef MODEL_SECOND_ORDER
    double a = RADAU_MU_REAL / s->h_lu, c[N_H];
    for (int i = 0; i < N_H; i++) c[i] = b[i] / a;
    reduced(s, b, c, b + N_H);
    lu_solve(s->lu_real, s->piv_real, b + N_H, N_H);
    for (int i = 0; i < N_H; i++) b[i] = (b[i] + b[N_H + i]) / a;
#else
    lu_solve(s->lu_real, s->piv_real, b, N_X);
#endif
}

/* (br, bi) (N_X each) = (MU_COMPLEX/h - J)^-1 (br, bi), h that of the factors */
static void solve_complex(const Radau *s, double *br, double *bi)
{
#ifdef MODEL_SECOND_ORDER
    double ar = RADAU_MU_COMPLEX_RE / s->h_lu, ai = RADAU_MU_COMPLEX_IM / s->h_lu, a2 = ar * ar + ai * ai;
    double cr[N_H], ci[N_H];
    for (int i = 0; i < N_H; i++) {  /* c = b1 / a */
        cr[i] = (br[i] * ar + bi[i] * ai) / a2;
        ci[i] = (bi[i] * ar - br[i] * ai) / a2;
    }
    reduced(s, br, cr, br + N_H);
    reduced(s, bi, ci, bi + N_H);
    lu_solve_complex(s->lu_complex_re, s->lu_complex_im, s->piv_complex, br + N_H, bi + N_H);
    for (int i = 0; i < N_H; i++) {  /* x1 = (b1 + x2) / a */
        double xr = br[i] + br[N_H + i], xi = bi[i] + bi[N_H + i];
        br[i] = (xr * ar + xi * ai) / a2;
        bi[i] = (xi * ar - xr * ai) / a2;
    }
#else
    lu_solve_complex(s->lu_complex_re, s->lu_complex_im, s->piv_complex, br, bi);
#endif
}

/* the dense output y (N_X) at t from the last step's interpolant */
static void dense(const Radau *s, double t, double *y)
{
    double x = (t - s->t_old) / s->h_last;
    for (int i = 0; i < N_X; i++)
        y[i] = s->Q[3 * N_X + i] + x * (s->Q[i] + x * (s->Q[N_X + i] + x * s->Q[2 * N_X + i]));
}

/* the collocation system by simplified Newton (scipy's solve_collocation_system): 1 when converged, the
   stage increments into Z (3 x N_X), the iterations and the convergence rate (-1: none) */
static int newton(SymmechModel *m, double t, const double *y, double h, double *Z, const double *scale,
                  double tol, int *iterations, double *rate)
{
    Radau *s = &m->radau;
    double W[3 * N_X], F[3 * N_X], TF[3 * N_X], dW[3 * N_X], z[N_X], wc[2 * N_X];
    double norm_old = -1.0;
    int k;
    mix(RADAU_TI, 3, Z, W);
    *rate = -1.0;
    for (k = 0; k < RADAU_NEWTON_MAXITER; k++) {
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < N_X; j++) z[j] = y[j] + Z[i * N_X + j];
            if (rates(m, t + RADAU_C[i] * h, z, F + i * N_X) != 0) { *iterations = k + 1; return 0; }
        }
        mix(RADAU_TI, 3, F, TF);
        for (int i = 0; i < N_X; i++) {
            double wr = W[N_X + i], wi = W[2 * N_X + i];
            dW[i] = TF[i] - RADAU_MU_REAL / h * W[i];
            wc[i] = TF[N_X + i] - (RADAU_MU_COMPLEX_RE * wr - RADAU_MU_COMPLEX_IM * wi) / h;
            wc[N_X + i] = TF[2 * N_X + i] - (RADAU_MU_COMPLEX_RE * wi + RADAU_MU_COMPLEX_IM * wr) / h;
        }
        solve_real(s, dW);
        solve_complex(s, wc, wc + N_X);
        memcpy(dW + N_X, wc, sizeof wc);
        double norm = scaled_rms(dW, 3 * N_X, scale);
        if (norm_old >= 0.0) *rate = norm / norm_old;
        if (!isfinite(norm)) break;
        if (*rate >= 0.0 && (*rate >= 1.0 || pow(*rate, RADAU_NEWTON_MAXITER - k) / (1.0 - *rate) * norm > tol))
            break;
        for (int i = 0; i < 3 * N_X; i++) W[i] += dW[i];
        mix(RADAU_T, 3, W, Z);
        if (norm == 0.0 || (*rate >= 0.0 && *rate / (1.0 - *rate) * norm < tol)) { *iterations = k + 1; return 1; }
        norm_old = norm;
    }
    *iterations = k < RADAU_NEWTON_MAXITER ? k + 1 : RADAU_NEWTON_MAXITER;
    return 0;
}

/* one collocation solve of length h from the integrator's point (scipy's _step_impl): fresh factors and, if
   Newton fails with an old Jacobian, a fresh one; 1 when converged, -1 on a failed rate or factor */
static int attempt(SymmechModel *m, double h, double *Z, int *iterations, double *rate)
{
    Radau *s = &m->radau;
    double scale[N_X];
    if (s->h_last != 0.0) {
        for (int i = 0; i < 3; i++) {
            dense(s, s->t + h * RADAU_C[i], Z + i * N_X);
            for (int j = 0; j < N_X; j++) Z[i * N_X + j] -= s->y[j];
        }
    } else {
        memset(Z, 0, 3 * N_X * sizeof(double));
    }
    error_scale(s, s->y, s->y, scale);
    double tol = fmax(10.0 * 2.220446049250313e-16 / s->rtol, fmin(0.03, sqrt(s->rtol)));
    double Z0[3 * N_X];
    memcpy(Z0, Z, sizeof Z0);
    for (;;) {
        if (!s->lu_valid && factor(s, h) != 0) return -1;
        if (newton(m, s->t, s->y, h, Z, scale, tol, iterations, rate)) return 1;
        if (s->jac_current) return 0;
        if (jacobian(m, s->t, s->y, s->f, s->J) != 0) return -1;
        s->jac_current = 1;
        s->lu_valid = 0;
        memcpy(Z, Z0, sizeof Z0);
    }
}

/* norm of the embedded order-3 error estimate, filtered by (MU_REAL/h - J)^-1 (again through f at the
   filtered point after a rejection) */
static double step_error(SymmechModel *m, const double *y_new, double h, const double *Z, int rejected)
{
    Radau *s = &m->radau;
    double ze[N_X], e[N_X], scale[N_X], fe[N_X], ye[N_X];
    mix(RADAU_E, 1, Z, ze);
    for (int i = 0; i < N_X; i++) { ze[i] /= h; e[i] = s->f[i] + ze[i]; }
    solve_real(s, e);
    error_scale(s, s->y, y_new, scale);
    double err = scaled_rms(e, N_X, scale);
    if (rejected && err > 1.0) {
        for (int i = 0; i < N_X; i++) ye[i] = s->y[i] + e[i];
        if (rates(m, s->t, ye, fe) != 0) return INFINITY;
        for (int i = 0; i < N_X; i++) fe[i] += ze[i];
        solve_real(s, fe);
        err = scaled_rms(fe, N_X, scale);
    }
    return err;
}

/* step factor from the error norms (Hairer and Wanner IV.8, scipy's predict_factor) */
static double predict_factor(double h, double h_old, double err, double err_old)
{
    double multiplier = 1.0;
    if (err_old >= 0.0 && h_old >= 0.0 && err != 0.0) multiplier = h / h_old * pow(err_old / err, 0.25);
    return err == 0.0 ? INFINITY : fmin(1.0, multiplier) * pow(err, -0.25);
}

/* one accepted step towards t_bound (scipy's Radau._step_impl); 0, or -1 below round-off or on a failure */
static int radau_step(SymmechModel *m, double t_bound)
{
    Radau *s = &m->radau;
    double Z[3 * N_X], y_new[N_X], err = 0.0, rate = -1.0, safety = 1.0;
    double min_step = 10.0 * fabs(nextafter(s->t, INFINITY) - s->t);
    double h_abs = s->h, h_old = s->h_old, err_old = s->err_old, t_new = s->t;
    int iterations = 0, rejected = 0;
    if (h_abs < min_step) { h_abs = min_step; h_old = err_old = -1.0; }
    for (;;) {
        if (h_abs < min_step) return -1;
        t_new = fmin(s->t + h_abs, t_bound);
        double h = t_new - s->t;
        h_abs = fabs(h);
        int ok = attempt(m, h, Z, &iterations, &rate);
        if (ok < 0) return -1;
        if (!ok) { h_abs *= 0.5; s->lu_valid = 0; continue; }
        for (int i = 0; i < N_X; i++) y_new[i] = s->y[i] + Z[2 * N_X + i];
        err = step_error(m, y_new, h, Z, rejected);
        safety = 0.9 * (2 * RADAU_NEWTON_MAXITER + 1) / (2 * RADAU_NEWTON_MAXITER + iterations);
        if (err <= 1.0) break;
        h_abs *= fmax(RADAU_MIN_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old));
        s->lu_valid = 0;
        rejected = 1;
    }
    int recompute = iterations > 2 && rate > 1e-3;
    double grow = fmin(RADAU_MAX_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old));
    if (!recompute && grow < 1.2) grow = 1.0;
    else s->lu_valid = 0;
    s->t_old = s->t;
    s->h_last = t_new - s->t;
    mix(RADAU_PT, 3, Z, s->Q);
    memcpy(s->Q + 3 * N_X, s->y, sizeof s->y);
    s->t = t_new;
    memcpy(s->y, y_new, sizeof y_new);
    if (rates(m, s->t, s->y, s->f) != 0) return -1;
    if (recompute && jacobian(m, s->t, s->y, s->f, s->J) != 0) return -1;
    s->jac_current = recompute;
    s->h_old = s->h;
    s->err_old = err;
    s->h = h_abs * grow;
    return 0;
}

/* a fresh solve from the instance's time and state (scipy's Radau.__init__): first step, Jacobian */
static int radau_start(SymmechModel *m, double t_bound, double rtol, double atol)
{
    Radau *s = &m->radau;
    double scale[N_X], y1[N_X], f1[N_X], d[N_X];
    s->t = m->r[VR_TIME];
    memcpy(s->y, m->r + VR_X, sizeof s->y);
    s->rtol = rtol;
    s->atol = fmax(atol, RADAU_ATOL_FLOOR);
    s->h_old = s->err_old = -1.0;
    s->h_last = 0.0;
    s->lu_valid = 0;
    if (rates(m, s->t, s->y, s->f) != 0) return -1;
    double span = t_bound - s->t;  /* scipy's select_initial_step, error estimator of order 3 */
    error_scale(s, s->y, s->y, scale);
    double d0 = scaled_rms(s->y, N_X, scale), d1 = scaled_rms(s->f, N_X, scale);
    double h0 = fmin(d0 < 1e-5 || d1 < 1e-5 ? 1e-6 : 0.01 * d0 / d1, span);
    for (int i = 0; i < N_X; i++) y1[i] = s->y[i] + h0 * s->f[i];
    if (rates(m, s->t + h0, y1, f1) != 0) return -1;
    for (int i = 0; i < N_X; i++) d[i] = f1[i] - s->f[i];
    double d2 = scaled_rms(d, N_X, scale) / h0;
    double h1 = d1 <= 1e-15 && d2 <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / fmax(d1, d2), RADAU_POWER);
    s->h = fmin(fmin(100.0 * h0, h1), span);
    if (jacobian(m, s->t, s->y, s->f, s->J) != 0) return -1;
    s->jac_current = 1;
    return 0;
}

/* Radau IIA from r[VR_TIME] to t_end, stepping up to max(t_end, horizon); resumed from where the last call
   left it when nothing in r[] has changed since, the state at t_end from the dense output */
static int radau(SymmechModel *m, double t_end, double rtol, double atol)
{
    Radau *s = &m->radau;
    int resume = s->h > 0.0 && s->rtol == rtol && s->atol == fmax(atol, RADAU_ATOL_FLOOR)
                 && memcmp(s->seen, m->r, sizeof s->seen) == 0;
    double t_bound = fmax(t_end, m->horizon);
    if (!resume && radau_start(m, t_bound, rtol, atol) != 0) return -1;
    while (s->t < t_end)
        if (radau_step(m, t_bound) != 0) { s->h = 0.0; return -1; }
    if (s->t == t_end) memcpy(m->r + VR_X, s->y, sizeof s->y);
    else dense(s, t_end, m->r + VR_X);
    m->r[VR_TIME] = t_end;
    m->dirty = 1;
    if (symmech_derivatives(m) != 0) { s->h = 0.0; return -1; }
    memcpy(s->seen, m->r, sizeof s->seen);
    return 0;
}
#endif

int symmech_integrate(SymmechModel *m, double t_end, double rtol, double atol)
{
    if (t_end <= m->r[VR_TIME]) return 0;
#ifdef MODEL_STIFF
    return radau(m, t_end, rtol, atol);
#else
    return dop853(m, t_end, rtol, atol);
#endif
}
