/* Generic numerics of an exported symmech model: the linear solve of M y' = F (LU with partial
   pivoting) and Dormand and Prince's DOP853 with the error control of Hairer's dop853.f (the tableau in
   dop853_tableau.h is written from symmech/core/dop853.py). Hand-written; the physics is generated. */
#include <math.h>
#include <string.h>

#include "symmech_model.h"
#include "dop853_tableau.h"

void symmech_reset(SymmechModel *m)
{
    static const double start[N_REAL] = START_VALUES;
    memcpy(m->r, start, sizeof start);
    m->dirty = 1;
}

/* solve a x = b in place (a n x n row-major, overwritten by its LU factors); 0, or -1 when singular */
static int solve_dense(double *a, double *b, int n)
{
    for (int k = 0; k < n; k++) {
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[pivot * n + k])) pivot = i;
        if (a[pivot * n + k] == 0.0) return -1;
        if (pivot != k) {
            for (int j = 0; j < n; j++) {
                double s = a[k * n + j]; a[k * n + j] = a[pivot * n + j]; a[pivot * n + j] = s;
            }
            double s = b[k]; b[k] = b[pivot]; b[pivot] = s;
        }
        for (int i = k + 1; i < n; i++) {
            double f = a[i * n + k] / a[k * n + k];
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; j++) a[i * n + j] -= f * a[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = b[i];
        for (int j = i + 1; j < n; j++) s -= a[i * n + j] * b[j];
        b[i] = s / a[i * n + i];
    }
    return 0;
}

/* y' at (t, y) with the instance's inputs and parameters */
static int rates(SymmechModel *m, double t, const double *y, double *out)
{
    double *mass = m->mass;
    const double *p = m->r + VR_P;
    MODEL_RATE(t, y, p, out);
    for (int k = 0; k < N_U; k++) out[U_ROW + k] += m->r[VR_U + k];
#ifdef MODEL_RATE_MASS
    MODEL_RATE_MASS(t, y, p, mass);
    return solve_dense(mass, out, N_X);
#else
    (void)mass;  /* M is the identity */
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

/* one DOP853 step of size h from (t, y) whose first stage k[0] is set: the stages k[1..], y1 = y(t + h) */
static int dop853_step(SymmechModel *m, double t, const double *y, double h, double k[][N_X], double *y1)
{
    double z[N_X];
    for (int s = 1; s < DOP853_STAGES; s++) {
        for (int i = 0; i < N_X; i++) {
            double sum = 0.0;
            for (int j = 0; j < s; j++) sum += DOP853_A[s][j] * k[j][i];
            z[i] = y[i] + h * sum;
        }
        if (rates(m, t + DOP853_C[s] * h, z, k[s]) != 0) return -1;
    }
    for (int i = 0; i < N_X; i++) {
        double sum = 0.0;
        for (int j = 0; j < DOP853_STAGES; j++) sum += DOP853_B[j] * k[j][i];
        y1[i] = y[i] + h * sum;
    }
    return 0;
}

#if N_Z > 0
/* the lowest indicator among those positive in z0 at (t, y): their falls through zero */
static double falling(SymmechModel *m, double t, const double *y, const double *z0)
{
    double z[N_Z], lowest = INFINITY;
    MODEL_EVENTS(t, y, m->r + VR_P, z);
    for (int i = 0; i < N_Z; i++)
        if (z0[i] > 0.0 && z[i] < lowest) lowest = z[i];
    return lowest;
}

/* The accepted step h from (t, y) (first stage k[0]) to y1 crossed an indicator that was positive in z0: the
   first time of the fall, located by the Illinois method on the step's own length (a step of DOP853 from
   (t, y) to each trial time, shorter than one it accepted). Leaves the state just past it (indicator <= 0) in
   y1 and returns its length (-1 on a failed rate). */
static double locate(SymmechModel *m, double t, const double *y, double h, double k[][N_X], const double *z0,
                     double *y1)
{
    double lo = 0.0, hi = h, f_lo = INFINITY, f_hi = falling(m, t + h, y1, z0), trial[N_X];
    for (int i = 0; i < N_Z; i++)
        if (z0[i] > 0.0 && z0[i] < f_lo) f_lo = z0[i];
    int side = 0;
    for (int it = 0; it < 200 && hi - lo > 4 * 2.2e-16 * fmax(fabs(t), fabs(h)); it++) {
        double s = hi - f_hi * (hi - lo) / (f_hi - f_lo);
        if (!(s > lo && s < hi)) s = 0.5 * (lo + hi);
        if (dop853_step(m, t, y, s, k, trial) != 0) return -1.0;
        double f = falling(m, t + s, trial, z0);
        if (f > 0.0) {
            lo = s; f_lo = f;
            if (side == -1) f_hi *= 0.5;
            side = -1;
        } else {
            hi = s; f_hi = f;
            memcpy(y1, trial, sizeof trial);
            if (side == 1) f_lo *= 0.5;
            side = 1;
        }
    }
    return hi;
}
#endif

int symmech_event_update(SymmechModel *m)
{
#if N_Z > 0
    double after[N_X];
    int changed = 0;
    if (symmech_derivatives(m) != 0) return -1;
    for (int i = 0; i < N_Z; i++) {
        if (m->r[VR_Z + i] > 0.0) continue;
        MODEL_EVENT_MAP(m->r + VR_X, m->r + VR_P, after);
        for (int j = 0; j < N_X; j++) {
            if (!isfinite(after[j])) return -1;
            changed |= after[j] != m->r[VR_X + j];
        }
        memcpy(m->r + VR_X, after, sizeof after);
        m->dirty = 1;
        if (symmech_derivatives(m) != 0) return -1;
    }
    return changed;
#else
    (void)m;
    return 0;
#endif
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

int symmech_integrate(SymmechModel *m, double t_end, double rtol, double atol)
{
    double k[DOP853_STAGES + 1][N_X], y1[N_X];
    double *y = m->r + VR_X;
    double t = m->r[VR_TIME];
    if (t_end <= t) return 0;
    if (rates(m, t, y, k[0]) != 0) return -1;
#if N_Z > 0
    double z0[N_Z];
    MODEL_EVENTS(t, y, m->r + VR_P, z0);
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
        if (err <= 1.0) {
            double factor = err == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -1.0 / 8.0));
#if N_Z > 0
            if (falling(m, t + h, y1, z0) <= 0.0) {  /* an event in the step: stop there, map the state */
                double s = locate(m, t, y, h, k, z0, y1);
                if (s < 0.0) return -1;
                t += s;
                memcpy(y, y1, sizeof y1);
                m->r[VR_TIME] = t;
                m->dirty = 1;
                if (symmech_event_update(m) < 0 || rates(m, t, y, k[0]) != 0) return -1;
                MODEL_EVENTS(t, y, m->r + VR_P, z0);
                h *= factor;
                continue;
            }
#endif
            t = last ? t_end : t + h;
            memcpy(y, y1, sizeof y1);
            memcpy(k[0], k[DOP853_STAGES], sizeof k[0]);
#if N_Z > 0
            MODEL_EVENTS(t, y, m->r + VR_P, z0);
            for (int i = 0; i < N_Z; i++)
                if (z0[i] < -EVENT_TOLERANCE) { m->r[VR_TIME] = t; m->dirty = 1; return -2; }
#endif
            h *= factor;
        } else {
            h *= fmax(0.2, 0.9 * pow(err, -1.0 / 8.0));
        }
    }
    m->r[VR_TIME] = t_end;
    m->dirty = 1;
    return symmech_derivatives(m);
}
