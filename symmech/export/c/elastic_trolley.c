/* The elastic trolley's model functions around its generated assembly (elastic_assembly.c, derived from the
   model's invariants by symmech.trolley.elastic.symbolic_assembly at export time): the frame's 12 channels and
   the arc length s are read at t from their cubic spline table (written above by `symmech export`, the
   compiled engine's nodes and coefficients) and passed to the generated functions after the rollers'
   parameters. Hand-written: a table lookup and argument packing, no physics.
   State y = (q, q'), 2 EL_N; M y' = F with M = diag(1, M(q)), F = (q', -R). */
#include <string.h>

/* the generated assembly's first parameters: the rollers' stiffnesses, dampings and preloads (5 each); the
   FMU's parameters p are the first EL_ROLLER_PARAMS of them, the others 0 (the preloads of the linear law) */
#define ASSEMBLY_ROLLER_PARAMS 15

void elastic_assembly_rate(double t, const double *y, const double *p, double *out);
void elastic_assembly_rate_mass(double t, const double *y, const double *p, double *out);
void elastic_assembly_outputs(const double *arg, double *out);

/* the 12 frame channels and s at t (EL_CHANNELS + 1), clamped to the table */
static void channels(double t, double *ch)
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
}

/* the generated module's parameters: the rollers' (p), then the channels at t, then s */
static void assembly_params(double t, const double *p, double *out)
{
    memset(out, 0, ASSEMBLY_ROLLER_PARAMS * sizeof(double));
    memcpy(out, p, EL_ROLLER_PARAMS * sizeof(double));
    channels(t, out + ASSEMBLY_ROLLER_PARAMS);
}

void elastic_trolley_rate(double t, const double *y, const double *p, double *out)
{
    double pa[ASSEMBLY_ROLLER_PARAMS + EL_CHANNELS + 1];
    assembly_params(t, p, pa);
    elastic_assembly_rate(t, y, pa, out);
}

void elastic_trolley_rate_mass(double t, const double *y, const double *p, double *out)
{
    double pa[ASSEMBLY_ROLLER_PARAMS + EL_CHANNELS + 1];
    assembly_params(t, p, pa);
    elastic_assembly_rate_mass(t, y, pa, out);
}

/* s [m], then the generated outputs (P0..P5, d1..d5, per probe u, e, n) at (t, y) with y' = dy */
void elastic_trolley_outputs(double t, const double *y, const double *dy, const double *p, double *out)
{
    double arg[3 * EL_N + ASSEMBLY_ROLLER_PARAMS + EL_CHANNELS + 1];
    memcpy(arg, y, 2 * EL_N * sizeof(double));
    memcpy(arg + 2 * EL_N, dy + EL_N, EL_N * sizeof(double));
    assembly_params(t, p, arg + 3 * EL_N);
    out[0] = arg[3 * EL_N + ASSEMBLY_ROLLER_PARAMS + EL_CHANNELS];
    elastic_assembly_outputs(arg, out + 1);
}
