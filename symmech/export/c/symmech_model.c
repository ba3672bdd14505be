/* Generic numerics of an exported symmech model: the linear solve of M y' = F (LU with partial
   pivoting) and Dormand and Prince's DOP853 with the error control of Hairer's dop853.f (the tableau in
   dop853_tableau.h is written from symmech/numerics/dop853.py). Hand-written; the physics is generated. */
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
    MODEL_RATE_MASS(t, y, p, mass);
    return solve_dense(mass, out, N_X);
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
    m->dirty = 0;
    return 0;
}

int symmech_integrate(SymmechModel *m, double t_end, double rtol, double atol)
{
    double k[DOP853_STAGES + 1][N_X], y1[N_X], z[N_X];
    double *y = m->r + VR_X;
    double t = m->r[VR_TIME];
    if (t_end <= t) return 0;
    if (rates(m, t, y, k[0]) != 0) return -1;
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
            t = last ? t_end : t + h;
            memcpy(y, y1, sizeof y1);
            memcpy(k[0], k[DOP853_STAGES], sizeof k[0]);
            h *= err == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -1.0 / 8.0));
        } else {
            h *= fmax(0.2, 0.9 * pow(err, -1.0 / 8.0));
        }
    }
    m->r[VR_TIME] = t_end;
    m->dirty = 1;
    return symmech_derivatives(m);
}
