/* The elastic trolley's model functions around its generated assembly (elastic_assembly.c, derived from the
   model's invariants by symmech.trolley.elastic.symbolic_assembly at export time): the frame's table (written
   above by `symmech export`, the compiled engine's nodes and cubic coefficients) is read and passed to the
   generated functions after the rollers' parameters. Hand-written: a table lookup and argument packing, no
   physics.
   At a prescribed speed the table is in t: the 12 frame channels and the arc length s (EL_COLUMNS = 13), and
   y = (q, q'), M y' = F with M = diag(1, M(q)). Under traction (EL_TRACTION) it is in s = y[EL_N]: the 15
   geometry channels, and y = (q, s, q', V0), M = diag(1, L); outside the table's arc lengths the channels are
   NaN, so the rates are not finite and the FMU reports an error instead of extrapolating the track. */
#include <math.h>
#include <string.h>

#include "model.h"

/* the generated assembly's first parameters: the rollers' stiffnesses, dampings and preloads (5 each); the
   FMU's parameters p are the first EL_ROLLER_PARAMS of them, the others 0 (the preloads of the linear law) */
#define ASSEMBLY_ROLLER_PARAMS 15
#define ASSEMBLY_PARAMS (ASSEMBLY_ROLLER_PARAMS + EL_COLUMNS)

void elastic_assembly_rate_and_mass_block(double t, const double *y, const double *p, double *out);
void elastic_assembly_outputs(const double *arg, double *out);

/* the EL_COLUMNS table columns at x (t, or s under traction): clamped to the table in t, NaN outside it in s */
static void columns(double x, double *ch)
{
#ifdef EL_TRACTION
    if (!(x >= EL_NODES_AT[0] && x <= EL_NODES_AT[EL_NODES - 1])) {
        for (int j = 0; j < EL_COLUMNS; j++) ch[j] = NAN;
        return;
    }
#endif
    int lo = 0, hi = EL_NODES - 2;
    while (lo < hi) {  /* the last node <= x */
        int mid = (lo + hi + 1) / 2;
        if (EL_NODES_AT[mid] <= x) lo = mid; else hi = mid - 1;
    }
    double h = x - EL_NODES_AT[lo];
    for (int j = 0; j < EL_COLUMNS; j++) {
        const double *c = EL_TABLE + (size_t)(lo * EL_COLUMNS + j) * 4;
        ch[j] = ((c[0] * h + c[1]) * h + c[2]) * h + c[3];
    }
}

/* the generated module's parameters: the rollers' (p), then the table's columns at t or s */
static void assembly_params(double t, const double *y, const double *p, double *out)
{
    memset(out, 0, ASSEMBLY_ROLLER_PARAMS * sizeof(double));
    memcpy(out, p, EL_ROLLER_PARAMS * sizeof(double));
#ifdef EL_TRACTION
    (void)t;
    columns(y[EL_N], out + ASSEMBLY_ROLLER_PARAMS);
#else
    (void)y;
    columns(t, out + ASSEMBLY_ROLLER_PARAMS);
#endif
}

/* F and M22 from one table lookup and one generated function (their common subexpressions formed once) */
void elastic_trolley_rate_and_mass_block(double t, const double *y, const double *p, double *f, double *mass)
{
    enum { N_M = N_X - MASS_IDENTITY };
    double pa[ASSEMBLY_PARAMS], out[N_X + N_M * N_M];
    assembly_params(t, y, p, pa);
    elastic_assembly_rate_and_mass_block(t, y, pa, out);
    memcpy(f, out, N_X * sizeof(double));
    memcpy(mass, out + N_X, N_M * N_M * sizeof(double));
}

/* at a prescribed speed s [m] first; then the generated outputs (P0..P5, d1..d5, per probe u, e, n) at (t, y)
   with y' = dy: they read y, the accelerations y'[DX_FIRST:] and the parameters */
void elastic_trolley_outputs(double t, const double *y, const double *dy, const double *p, double *out)
{
    double arg[N_X + N_DX + ASSEMBLY_PARAMS];
    memcpy(arg, y, N_X * sizeof(double));
    memcpy(arg + N_X, dy + DX_FIRST, N_DX * sizeof(double));
    assembly_params(t, y, p, arg + N_X + N_DX);
#ifndef EL_TRACTION
    *out++ = arg[N_X + N_DX + ASSEMBLY_PARAMS - 1];
#endif
    elastic_assembly_outputs(arg, out);
}
