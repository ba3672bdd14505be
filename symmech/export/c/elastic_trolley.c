/* Generic assembly of the elastic trolley's equations from its invariants (hand-written; the invariants, the
   frame table and the output fields are the data written above by `symmech export` from the Python model,
   symmech.trolley.elastic.kernels.pack). The same sums as the compiled engine's _terms, _resultants and
   elastic.outputs: M(q) q'' + R(t, q, q') = 0 with the frame's motion from a cubic spline table in t.
   State y = (q, q'), 2 EL_N; M y' = F with M = diag(1, M(q)), F = (q', -R). */
#include <math.h>
#include <string.h>

/* the 12 frame channels (load a0 + g0 nu, omega, omega', v0) and the arc length s at t, clamped to the table */
static double channels(double t, double *ch)
{
    int lo = 0, hi = EL_NODES - 2;
    while (lo < hi) {  /* the last node <= t */
        int mid = (lo + hi + 1) / 2;
        if (EL_TIMES[mid] <= t) lo = mid; else hi = mid - 1;
    }
    double x = t - EL_TIMES[lo];
    for (int j = 0; j <= EL_CHANNELS; j++) {
        const double *c = EL_TABLE + (size_t)(lo * (EL_CHANNELS + 1) + j) * 4;
        ch[j] = ((c[0] * x + c[1]) * x + c[2]) * x + c[3];
    }
    return ch[EL_CHANNELS];
}

/* B = skew(omega') + skew(omega)^2 and W = skew(omega), row-major 3 x 3 */
static void frame_mats(const double *ch, double *B, double *W)
{
    const double *w = ch + 3, *dw = ch + 6;
    double S[9] = {0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0};
    memcpy(W, S, sizeof S);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++) s += S[i * 3 + k] * S[k * 3 + j];
            B[i * 3 + j] = s;
        }
    B[1] -= dw[2]; B[2] += dw[1]; B[5] -= dw[0];
    B[3] += dw[2]; B[6] -= dw[1]; B[7] += dw[0];
}

/* coefficients of r + sum q_a phi_a + 1/2 sum q_a q_b psi_ab over the fields (EL_F) */
static void field_position(const double *q, double *rr)
{
    rr[0] = 1.0;
    for (int a = 0; a < EL_N; a++) rr[1 + a] = q[a];
    for (int p = 0; p < EL_PAIRS; p++)
        rr[1 + EL_N + p] = (EL_PAIR_I[p] == EL_PAIR_J[p] ? 0.5 : 1.0) * q[EL_PAIR_I[p]] * q[EL_PAIR_J[p]];
}

/* y A(x) (EL_F) */
static void times_a(const double *y, const double *x, double *out)
{
    memset(out, 0, EL_F * sizeof(double));
    for (int b = 0; b < EL_N; b++) {
        out[1 + b] = y[b];
        for (int e = EL_PTR[b]; e < EL_PTR[b + 1]; e++) out[EL_COL[e]] += y[b] * x[EL_QI[e]];
    }
}

/* second-order field rates sum q'_a q'_b psi_ab (EL_F; zero on the rigid and first-order fields) */
static void quadratic_rates(const double *qd, double *p2)
{
    times_a(qd, qd, p2);
    for (int k = 0; k <= EL_N; k++) p2[k] = 0.0;
}

/* X_k = sum_l G_kl x_l (EL_F x 9) */
static void gram_pass(const double *x, double *X)
{
    for (int r = 0; r < 9 * EL_F; r++) {
        const double *g = EL_GX + (size_t)r * EL_F;
        double s = 0.0;
        for (int l = 0; l < EL_F; l++) s += g[l] * x[l];
        X[r] = s;
    }
}

/* roller deflections d (5) and forces P1..P5 (5) [m, N]; p = the rollers' stiffnesses (5) [N/m] and
   dampings (5) [N s/m], the FMU's parameters */
static void rollers(const double *q, const double *qd, const double *p, double *d, double *force)
{
    for (int r = 0; r < 5; r++) {
        double dr = 0.0, ddr = 0.0;
        for (int j = 0; j < 5; j++) { dr += EL_C[r * 5 + j] * q[j]; ddr += EL_C[r * 5 + j] * qd[j]; }
        double k = p[r], c = p[5 + r], pre = EL_PRELOAD[r];
        d[r] = dr;
        if (EL_CLAMPED) force[r] = k * (fmax(pre - dr, 0.0) - fmax(pre + dr, 0.0)) - c * ddr;
        else force[r] = -k * dr - c * ddr;
    }
}

/* R(t, q, q') (EL_N) of M q'' + R = 0 at the parameters p */
static void residual(double t, const double *q, const double *qd, const double *p, double *R)
{
    double ch[EL_CHANNELS + 1], B[9], W[9], rr[EL_F], v[EL_F], p2[EL_F], z[EL_F];
    static double X[9 * EL_F], Y[9 * EL_F];  /* too large for small stacks; one instance at a time */
    channels(t, ch);
    frame_mats(ch, B, W);
    field_position(q, rr);
    times_a(qd, q, v);
    quadratic_rates(qd, p2);
    gram_pass(rr, X);
    gram_pass(v, Y);
    for (int k = 0; k < EL_F; k++) {
        double s = 0.0;
        for (int j = 0; j < 3; j++) s += EL_S1[k * 3 + j] * ch[j];
        for (int l = 0; l < EL_F; l++) s += EL_GTR[k * EL_F + l] * p2[l];
        for (int m = 0; m < 9; m++) s += X[k * 9 + m] * B[m] + 2.0 * Y[k * 9 + m] * W[m];
        z[k] = s;
    }
    for (int b = 0; b < EL_N; b++) {
        double s = z[1 + b];
        for (int e = EL_PTR[b]; e < EL_PTR[b + 1]; e++) s += q[EL_QI[e]] * z[EL_COL[e]];
        for (int j = 0; j < EL_N; j++) s += EL_K[b * EL_N + j] * q[j] + EL_D[b * EL_N + j] * qd[j];
        R[b] = s;
    }
    for (int blk = 0; blk < EL_BLOCKS; blk++) {  /* held beams' membrane force */
        const int *idx = EL_BLOCK_INDEX + blk * EL_BLOCK_WIDTH;
        const double *H = EL_BLOCK_H + (size_t)blk * EL_BLOCK_WIDTH * EL_BLOCK_WIDTH;
        int m = EL_BLOCK_SIZE[blk];
        double hx[EL_BLOCK_WIDTH], quad = 0.0;
        for (int i = 0; i < m; i++) {
            hx[i] = 0.0;
            for (int j = 0; j < m; j++) hx[i] += H[i * EL_BLOCK_WIDTH + j] * q[idx[j]];
            quad += q[idx[i]] * hx[i];
        }
        for (int i = 0; i < m; i++) R[idx[i]] += 4.0 * EL_BLOCK_C[blk] * quad * hx[i];
    }
    if (EL_ROLLERS_ON) {
        double d[5], force[5];
        rollers(q, qd, p, d, force);
        for (int j = 0; j < 5; j++)
            for (int r = 0; r < 5; r++) R[j] -= force[r] * EL_C[r * 5 + j];
    }
}

void elastic_trolley_rate(double t, const double *y, const double *p, double *out)
{
    double R[EL_N];
    residual(t, y, y + EL_N, p, R);
    for (int a = 0; a < EL_N; a++) { out[a] = y[EL_N + a]; out[EL_N + a] = -R[a]; }
}

/* M = diag(1, A Gtr A^T), (2 EL_N)^2 row-major */
void elastic_trolley_rate_mass(double t, const double *y, const double *p, double *out)
{
    (void)t; (void)p;
    static double AG[EL_N * EL_F];
    const int n2 = 2 * EL_N;
    memset(out, 0, (size_t)n2 * n2 * sizeof(double));
    for (int a = 0; a < EL_N; a++) out[a * n2 + a] = 1.0;
    for (int b = 0; b < EL_N; b++)
        for (int j = 0; j < EL_F; j++) {
            double s = EL_GTR[(1 + b) * EL_F + j];
            for (int e = EL_PTR[b]; e < EL_PTR[b + 1]; e++) s += y[EL_QI[e]] * EL_GTR[EL_COL[e] * EL_F + j];
            AG[b * EL_F + j] = s;
        }
    for (int b = 0; b < EL_N; b++)
        for (int j = 0; j < EL_N; j++) {
            double s = AG[j * EL_F + 1 + b];
            for (int e = EL_PTR[b]; e < EL_PTR[b + 1]; e++) s += y[EL_QI[e]] * AG[j * EL_F + EL_COL[e]];
            out[(EL_N + b) * n2 + EL_N + j] = s;
        }
}

static void cross(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* the probe fields (3) of the coefficient vector c at probe k */
static void probe(const double *c, int k, const double *mask, double *out)
{
    for (int i = 0; i < 3; i++) {
        double s = 0.0;
        for (int f = 0; f < EL_F; f++)
            s += (mask ? mask[f] : 1.0) * c[f] * EL_PROBE_FIELDS[(f * EL_PROBES + k) * 3 + i];
        out[i] = s;
    }
}

/* the outputs at (t, y) with y' = dy: s [m], P0..P5 [N], roller deflections d1..d5 [m], then per probe its
   displacement u (3) [m], elastic deflection e (3) [m] and overload n (3) [g] (elastic.outputs) */
void elastic_trolley_outputs(double t, const double *y, const double *dy, const double *p, double *out)
{
    const double *q = y, *qd = y + EL_N, *qdd = dy + EL_N;
    double ch[EL_CHANNELS + 1], B[9], W[9], rr[EL_F], v[EL_F], acc[EL_F], p2[EL_F];
    out[0] = channels(t, ch);
    frame_mats(ch, B, W);
    field_position(q, rr);
    times_a(qd, q, v);
    quadratic_rates(qd, p2);
    times_a(qdd, q, acc);
    for (int f = 0; f < EL_F; f++) acc[f] += p2[f];
    double first[3] = {0.0, 0.0, 0.0}, fv[3] = {0.0, 0.0, 0.0}, fa[3] = {0.0, 0.0, 0.0};
    for (int f = 0; f < EL_F; f++)
        for (int j = 0; j < 3; j++) {
            first[j] += rr[f] * EL_S1[f * 3 + j]; fv[j] += v[f] * EL_S1[f * 3 + j]; fa[j] += acc[f] * EL_S1[f * 3 + j];
        }
    out[1] = EL_MASS * ch[0] + fa[0];  /* P0 = F1, the resultant along x1 */
    for (int j = 0; j < 3; j++) out[1] += B[j] * first[j] + 2.0 * W[j] * fv[j];
    double d[5], force[5];
    rollers(q, qd, p, d, force);
    for (int r = 0; r < 5; r++) { out[2 + r] = force[r]; out[7 + r] = d[r]; }
    for (int k = 0; k < EL_PROBES; k++) {
        double pos[3], vel[3], ddu[3], a[3], wp[3], wwp[3], dwp[3], wv[3];
        double *o = out + 12 + 9 * k;
        probe(rr, k, NULL, pos);
        probe(v, k, NULL, vel);
        probe(acc, k, NULL, ddu);
        probe(rr, k, EL_ELASTIC, o + 3);
        cross(ch + 3, pos, wp); cross(ch + 3, wp, wwp); cross(ch + 6, pos, dwp); cross(ch + 3, vel, wv);
        for (int i = 0; i < 3; i++) {
            a[i] = ch[i] + dwp[i] + wwp[i] + 2.0 * wv[i] + ddu[i];
            o[i] = pos[i] - EL_PROBE_POINTS[k * 3 + i];
            o[6 + i] = a[i] / EL_G_REF;
        }
    }
}
