/* symmech exported model: the state of one instance and the generic numerics around the generated
   equations (hand-written: no physics here; the physics is the generated C99 module that model.h names).

   Every Float64 variable lives in r[], indexed by its FMI value reference (layout in model.h):
   r[VR_TIME] time [s], then the N_X continuous states, the derivatives that are not states, the N_Y
   calculated outputs (MODEL_OUTPUTS, when the model has them), the N_U
   inputs, the N_P parameters and the N_D discrete states of a model with regimes.

   What model.h names (the generated physics, M y' = F): MODEL_RATE(t, y, p, F) with M the identity, or with
   M = diag(I, M22), MASS_IDENTITY identity rows, and MODEL_RATE_MASS(t, y, p, M) (M whole, row by row); or, instead
   of both, MODEL_RATE_AND_MASS_BLOCK(t, y, p, F, M22) (F and M22 alone, row by row, in one call: their common
   subexpressions formed once); MASS_SPD where M22 is symmetric positive definite (Cholesky, its lower
   triangle read); MODEL_SECOND_ORDER where y = (x, x') with F's first N_X/2 rows x' (Radau then solves its
   Newton systems by the halves' Schur complement). */
#ifndef SYMMECH_MODEL_H
#define SYMMECH_MODEL_H

#include "model.h"

#ifdef MODEL_STIFF
/* Radau IIA (order 5) between calls of symmech_integrate: where the integrator stands, its step control,
   Jacobian and factors, and the collocation polynomial of its last step (the dense output) */
typedef struct {
    double t, y[N_X], f[N_X];
    double h, h_old, err_old;  /* next step, the one proposed before it, and its error norm (-1: none) */
    double t_old, h_last;      /* the last step: start and length (0: none) */
    double Q[4 * N_X];         /* its interpolant: coefficients of x, x^2, x^3 row by row, then y at t_old */
    double J[N_X * N_X];       /* dy'/dy */
    double lu_real[N_X * N_X];  /* MU_REAL/h - J (MODEL_SECOND_ORDER: its N_X/2 x N_X/2 Schur complement) */
    double lu_complex_re[N_X * N_X], lu_complex_im[N_X * N_X];  /* MU_COMPLEX/h - J: real and imaginary parts */
    int piv_real[N_X], piv_complex[N_X];
    double h_lu;  /* the step of the factors */
    int jac_current, lu_valid;
    double rtol, atol;
    double seen[N_REAL];  /* r[] when the last call returned: the integrator resumes only from there */
} Radau;
#endif

typedef struct {
    double r[N_REAL];
    double dx[N_X];  /* the state derivatives at r, valid while !dirty */
    double mass[N_X * N_X];  /* work space: M of M y' = F, overwritten by its LU factors */
    int dirty;
    double horizon;  /* the integrator may step up to this time and interpolate back (0: to each t_end only) */
    /* told of each notice of the model's event updates (MODEL_NOTICE: a rocking contact, the stop), with its
       time; NULL: not told */
    void (*notice)(void *env, double t, const char *message);
    void *notice_env;
#ifdef MODEL_STIFF
    Radau radau;
#endif
} SymmechModel;

/* start values of every variable, time 0 */
void symmech_reset(SymmechModel *m);
/* dx = y' of M y' = F + inputs at the instance's time, state, inputs and parameters; 0, or -1 where M is
   singular or a rate is not finite */
int symmech_derivatives(SymmechModel *m);
/* integrate from r[VR_TIME] to t_end (DOP853, or Radau IIA for a stiff model: MODEL_STIFF), error control
   rtol and atol (Radau: atol, at least RADAU_ATOL_FLOOR, times each state's nominal); with state events (DOP853
   only: a stiff model has none) each fall of an indicator through zero located on the step's dense output and
   the model's update applied there (symmech_event_update); 0, 1 where the model ended the simulation at an event
   (SYMMECH_STOP: r[VR_TIME] is then its time), or -1 on a singular M, a non-finite state or a step size below
   round-off, -2 where the motion left the model (symmech_left_model; r[VR_TIME] is then that time) */
int symmech_integrate(SymmechModel *m, double t_end, double rtol, double atol);
/* state events (N_Z > 0): at an indicator's fall through zero, the model's update of the state and its
   discrete states (MODEL_EVENT_UPDATE), its notice passed to m->notice; 1 when something changed, 0 when not,
   SYMMECH_STOP when the model ends the simulation there (and at every update after), -1 on a non-finite state. The
   importer calls it at the events it locates (Model Exchange), symmech_integrate at those it locates itself
   (Co-Simulation, the example program). */
int symmech_event_update(SymmechModel *m);
#define SYMMECH_STOP 2
/* the start: the derivatives, and the model's update where an event holds at the start values (a grain that
   starts on the surface lands: the update a Model Exchange importer asks for after the initialization, made for
   Co-Simulation and the example program too); 0, or -1 on a singular M or a non-finite state */
int symmech_start(SymmechModel *m);
/* 1 when an event indicator is below -EVENT_TOLERANCE: crossed without its event (an importer stepped over two
   of its zeros), the motion has left what the model covers; 0 otherwise */
int symmech_left_model(SymmechModel *m);
#define LEFT_MODEL_MESSAGE "the motion left what the model covers: an event indicator fell below zero without its " \
    "event"

#endif
