/* The grain's regimes as the discrete state of an exported model: flight, slip or stick decides which generated
   rates and event indicators hold, and at the events the native engine's transitions
   (symmech/grain/motion_engine: loop.py, landing.py, sliding_phase.py, slip.py) with its thresholds. Hand-written
   glue: every quantity of physics comes from the generated grain_motion and grain_sliding modules through the
   call_* gatherers written above this file by `symmech export` (with the offsets P_* of the parameters in p and
   D_* of the discrete states in d = p + N_P, r[VR_D...]). */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "symmech_model.h"

enum { FLIGHT, SLIP, STICK };
enum { NO_NOTICE, MAX_IMPACTS_NOTICE, ROCKING_NOTICE };  /* d[D_NOTICE]: what the last update tells */

static double *discrete(double *p) { return p + N_P; }

static int regime_of(const double *p) { return (int)p[N_P + D_REGIME]; }

void grain_rate(double t, const double *y, const double *p, double *out)
{
    switch (regime_of(p)) {
    case SLIP: call_slip_rate(t, y, p, NULL, out); break;
    case STICK: call_stick_rate(t, y, p, NULL, out); break;
    default: grain_motion_rate(t, y, p, out);
    }
}

/* flight: the gap and a constant 1; slip: s . ref - v_stop and n; stick: mu n - |phi| and n */
void grain_event_values(double t, const double *y, const double *p, double *out)
{
    switch (regime_of(p)) {
    case SLIP: call_slip_events(t, y, p, NULL, out); break;
    case STICK: call_stick_events(t, y, p, NULL, out); break;
    default: grain_motion_event_values(t, y, p, out); out[1] = 1.0;
    }
}

static double normal_force(double t, const double *p)
{
    double n;
    call_normal_force(t, NULL, p, NULL, &n);
    return n;
}

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static double largest_axis(const double *p) { return fmax(p[P_AXES], fmax(p[P_AXES + 1], p[P_AXES + 2])); }

/* the native engine's round-off floors of the gap [m] and of the contact velocity [m/s] (kinematics.py) */
static double gap_noise(const double *y, const double *p)
{
    return 64 * DBL_EPSILON * (largest_axis(p) + fabs(y[Y_RZ]) + p[P_AMPLITUDE]);
}

static double velocity_noise(const double *y, const double *p)
{
    double v = norm3(y + Y_VX), w = norm3(y + Y_W1);
    return 1e3 * DBL_EPSILON * (v + w * largest_axis(p) + p[P_AMPLITUDE] * p[P_OMEGA]);
}

/* the slip's reference direction (its event reads the slip along it): the slip's own direction now */
static void set_reference(double t, const double *y, double *p)
{
    double s[2];
    call_slip(t, y, p, NULL, s);
    double size = fmax(hypot(s[0], s[1]), 1e-300);
    discrete(p)[D_REF] = s[0] / size;
    discrete(p)[D_REF + 1] = s[1] / size;
}

/* The slowest slip the FMU lets start: 2 sqrt(eps) times the velocities' nominal, or the native engine's 2 v_stop
   if faster. An importer's difference-quotient Jacobian perturbs a velocity by sqrt(eps) times its magnitude; a
   slip below that turns its direction (at mu n |B| / |s|) faster than that Jacobian sees, and CVode creeps (about
   1e5 steps over the first 2 ms at rtol 1e-12, against 500 from 1e-9 m/s). */
static double slip_on_speed(const double *p)
{
    static const double nominal[N_X] = NOMINALS;
    return 2.0 * fmax(p[N_P + D_V_STOP], sqrt(DBL_EPSILON) * nominal[Y_VX]);
}

static void friction_impulse(double t, double *y, const double *p, const double *target)
{
    double after[N_X];
    call_friction_impulse(t, y, p, target, after);
    for (int i = 0; i < N_X; i++) y[i] = after[i];
}

/* slip.py's settle: a slip within 1.5 v_stop is removed by a friction impulse, into a stick when may_stick and
   the stick force is inside the cone, else into a slip along the slip direction at slip_on_speed; a faster slip
   goes on along its own direction, brought up to slip_on_speed by a friction impulse where slower (the FMU's
   difference: the native engine goes on at any speed) */
static void settle(double t, double *y, double *p, int may_stick)
{
    double *d = discrete(p), s[2], direction[2], target[FRICTION_IMPULSE_ARGS];
    call_slip(t, y, p, NULL, s);
    double speed = hypot(s[0], s[1]);
    d[D_REGIME] = SLIP;
    if (p[P_MU_S] > 0.0 && speed <= 1.5 * d[D_V_STOP]) {
        double phi[2];
        call_stick_force(t, y, p, NULL, phi);
        if (may_stick && hypot(phi[0], phi[1]) <= p[P_MU_S] * normal_force(t, p)) {
            target[0] = target[1] = 0.0;
            friction_impulse(t, y, p, target);
            d[D_REGIME] = STICK;
            return;
        }
        call_slip_direction(t, y, p, NULL, direction);
    } else {
        direction[0] = s[0] / fmax(speed, 1e-300);
        direction[1] = s[1] / fmax(speed, 1e-300);
    }
    if (p[P_MU_S] > 0.0 && (speed <= 1.5 * d[D_V_STOP] || speed < slip_on_speed(p))) {
        target[0] = slip_on_speed(p) * direction[0];
        target[1] = slip_on_speed(p) * direction[1];
        friction_impulse(t, y, p, target);
    }
    set_reference(t, y, p);
}

/* landing.py's land: the plastic normal impulse at the lowest point, the grain put on the plane (the centre at
   the support height, v_z = 0, an ellipsoid's tilting spin dropped) */
static void put_on_plane(double t, double *y, const double *p)
{
    double contact[CONTACT_SIZE], plastic[PLASTIC_SIZE], impulse[COULOMB_SIZE] = {0.0}, after[N_X];
    call_impact_contact(t, y, p, NULL, contact);
    call_plastic_impulse(t, y, p, contact, plastic);
    impulse[COULOMB_P + 2] = plastic[PLASTIC_P_I];
    call_impact_state(t, y, p, impulse, after);
    call_rest_on_plane(t, after, p, NULL, y);
}

/* a landing: put_on_plane, then the sliding phase's start (sliding_phase.py: v_stop = tolerance (|g| + |n|)
   scan_step, settled) */
static void land(double t, double *y, double *p)
{
    put_on_plane(t, y, p);
    double g = sqrt(p[P_G] * p[P_G] + p[P_G + 1] * p[P_G + 1] + p[P_G + 2] * p[P_G + 2]);
    discrete(p)[D_V_STOP] = p[P_TOLERANCE] * (g + fabs(normal_force(t, p))) * p[P_SCAN_STEP];
    settle(t, y, p, 1);
}

/* landing.py's bounce: the impact map, the impact counted; the contact point's normal velocity after it, or 0
   where ZENO_IMPACTS impacts fell within ZENO_INTERVAL periods (chattering: it lands) */
static double bounce(double t, double *y, double *p, const double *contact)
{
    double *d = discrete(p), plastic[PLASTIC_SIZE], coulomb[COULOMB_IMPULSE_ARGS], impulse[COULOMB_SIZE], after[N_X],
           contact_after[CONTACT_SIZE];
    call_plastic_impulse(t, y, p, contact, plastic);
    for (int i = 0; i < PLASTIC_SIZE; i++) coulomb[COULOMB_IMPULSE_ARG_P_I + i] = plastic[PLASTIC_P_I + i];
    coulomb[COULOMB_IMPULSE_ARG_U2] = contact[CONTACT_U + 2];
    call_coulomb_impulse(t, y, p, coulomb, impulse);
    call_impact_state(t, y, p, impulse, after);
    for (int i = 0; i < N_X; i++) y[i] = after[i];
    long n = (long)d[D_IMPACTS];
    d[D_TIMES + n % ZENO_IMPACTS] = t;
    d[D_IMPACTS] = (double)(n + 1);
    d[D_LAST_IMPACT] = t;
    if (n + 1 >= ZENO_IMPACTS && t - d[D_TIMES + (n + 1) % ZENO_IMPACTS] < ZENO_INTERVAL * p[P_PERIOD]) return 0.0;
    call_impact_contact(t, y, p, NULL, contact_after);
    return contact_after[CONTACT_U + 2];
}

/* A contact the native engine does not reach (flight_phase.py's fly, status "resting"): after the last bounce the
   next flight stays within the gap's round-off, the plane pulling away (n <= 0: no landing). Here the gap fell
   back through zero, the point approaching at u < 0 [m/s], after a hop since the last impact whose height
   |u| (t - t_last) / 4 (a parabola's) stayed within the gap's round-off. */
static int held_on_plane(double t, const double *y, const double *p, double u)
{
    const double *d = p + N_P;
    return normal_force(t, p) <= 0.0 && d[D_IMPACTS] > 0.0 && -u * (t - d[D_LAST_IMPACT]) / 4.0 <= gap_noise(y, p);
}

/* loop.py's flight branch at a contact (the gap at most its round-off, the point not leaving: the native engine
   locates the gap's falls only): a rocking contact where the grain is held on a plane that pulls away (loop.py:
   put on the plane, its tilting spin dropped, flying on; counted and told), the stop at numerics.max_impacts
   before a bounce, a bounce where the point approaches, then a landing where it leaves slower than rest_velocity
   (or touches without approaching) on a plane that pushes */
static int flight_event(double t, double *y, double *p)
{
    double *d = discrete(p), gap[N_Z], contact[CONTACT_SIZE], u_n = 0.0;
    int changed = 0;
    grain_motion_event_values(t, y, p, gap);
    if (gap[0] > gap_noise(y, p)) return 0;
    call_impact_contact(t, y, p, NULL, contact);
    if (contact[CONTACT_U + 2] > velocity_noise(y, p)) return 0;  /* the gap rising through zero after a bounce or a lift-off */
    if (contact[CONTACT_U + 2] < -velocity_noise(y, p)) {
        if (held_on_plane(t, y, p, contact[CONTACT_U + 2])) {
            put_on_plane(t, y, p);
            d[D_ROCKING] += 1.0;
            d[D_NOTICE] = ROCKING_NOTICE;
            return 1;
        }
        if (d[D_IMPACTS] >= p[P_MAX_IMPACTS]) {
            d[D_STOPPED] = 1.0;
            d[D_NOTICE] = MAX_IMPACTS_NOTICE;
            return SYMMECH_STOP;
        }
        u_n = bounce(t, y, p, contact);
        changed = 1;
    }
    if (u_n <= p[P_REST_VELOCITY] && normal_force(t, p) > 0.0) {
        land(t, y, p);
        changed = 1;
    }
    return changed;
}

/* outcome.py's warnings, as the FMU takes them */
const char *grain_notice(const double *p)
{
    switch ((int)p[N_P + D_NOTICE]) {
    case MAX_IMPACTS_NOTICE:
        return "the simulation ends at the contact after numerics.max_impacts impacts (parameter max_impacts), "
               "as the native engine stops";
    case ROCKING_NOTICE:
        return "a rocking contact: a tumbling ellipsoid held on the plane by its spin while the surface accelerates "
               "away; rocking is not modelled, so its tilting spin was dropped and it flies on (output rocking)";
    default: return NULL;
    }
}

int grain_event_update(double t, double *y, double *p)
{
    double z[N_Z];
    int regime = regime_of(p);
    discrete(p)[D_NOTICE] = NO_NOTICE;
    if (discrete(p)[D_STOPPED] != 0.0) return SYMMECH_STOP;
    if (regime == FLIGHT) return flight_event(t, y, p);
    grain_event_values(t, y, p, z);
    if (z[1] <= 0.0) {  /* the normal force reached zero: lift-off */
        discrete(p)[D_REGIME] = FLIGHT;
        return 1;
    }
    if (z[0] > 0.0) return 0;
    settle(t, y, p, regime == SLIP);  /* the slip stopped, or the stick force reached the cone */
    return 1;
}
