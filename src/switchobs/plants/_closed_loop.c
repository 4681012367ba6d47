/* The braking loop of switchobs.plants.simulate in C: quarter car, Burckhardt road schedule, five- or
 * two-phase ABS, optional XBS estimator, and the hybrid RK4 integrator with event location.
 *
 * A statement-for-statement port of switchobs/plants/_hybrid.py (integrate, rk4_step, locate_event,
 * _transitions), _plant.py (_QuarterCar), _road.py (_RoadState) and _controllers.py (the five- and
 * two-phase runtimes): the same floating-point operations in the same order (no contraction, the
 * system libm's exp and pow as Python's math), so that a run gives the same numbers as the Python loop.
 * Python prepends the index macros P_* (layout of the parameter vector), OUT_*, EV_*, ST_* and the
 * observer hooks OBS_NX, OBS_NS, OBS_STEP and OBS_READOUT (OBS_NX 0: no observer); with RECORD_STEP a row
 * also holds, after the columns of SERIES, the length of the step that ended there (0 in the first row), which
 * an estimator replayed over the run afterwards needs bit for bit.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

#define MAX_CASCADE 8
#define V_WHEEL_FLOOR 0.1
#define NY 4

typedef struct {
    const double *p;
    /* road (_RoadState): changes are rows of CH_COLS values */
    const double *ch;
    int n_ch, next, blending;
    double a1, a2, a3, b1, b2, b3, t0, dur;
    /* controller runtime */
    int kind, phase;
    double rates[6], thr[6][2], sgn[6][2];
    int nxt[6][2], ng[6];
    double ft0, T, ref0, ra2, ra3, target, deadline;
    double start;
    /* estimator */
    int est, use_hat;
    double xbs_hat, est_y, est_vx, estimate;
    double h_step;
    /* outputs of the last rhs evaluation */
    double o_lam, o_mu, o_xbs, o_omdot, o_ax, o_x2, o_u;
} Loop;

/* ------------------------------------------------------------------ road */
static void road_eval(Loop *L, double lam, double t, double *mu_out, double *xbs_out) {
    double al = lam < 0.0 ? -lam : lam;
    double c1 = L->a1, c2 = L->a2, c3 = L->a3;
    double e = exp(-c2 * al);
    double mu = c1 * (1.0 - e) - c3 * al;
    double xbs = c1 * c2 * e - c3;
    if (L->blending) {
        double s = (t - L->t0) / L->dur, w;
        if (s <= 0.0) w = 0.0;
        else if (s >= 1.0) w = 1.0;
        else w = s * s * (3.0 - 2.0 * s);
        c1 = L->b1; c2 = L->b2; c3 = L->b3;
        e = exp(-c2 * al);
        mu += w * (c1 * (1.0 - e) - c3 * al - mu);
        xbs += w * (c1 * c2 * e - c3 - xbs);
    }
    *mu_out = lam < 0.0 ? -mu : mu;
    *xbs_out = xbs;
}

static const double *road_pending(const Loop *L) {
    return L->next < L->n_ch ? L->ch + CH_COLS * L->next : NULL;
}

static void road_start_change(Loop *L, double t) {
    const double *c = road_pending(L);
    L->next += 1;
    L->b1 = c[CH_C1]; L->b2 = c[CH_C2]; L->b3 = c[CH_C3];
    L->t0 = t;
    L->dur = c[CH_DURATION];
    if (c[CH_DURATION] > 0.0) L->blending = 1;
    else { L->a1 = L->b1; L->a2 = L->b2; L->a3 = L->b3; }
}

static double road_breakpoint(const Loop *L) {
    const double *c;
    if (L->blending) return L->t0 + L->dur;
    c = road_pending(L);
    if (c != NULL && c[CH_AT_TIME] != 0.0) return c[CH_WHERE];
    return INFINITY;
}

/* ------------------------------------------------------------------ controllers */
static int tracked(const Loop *L) {
    return L->kind == 0 && L->p[P_TRACKING] != 0.0 && (L->phase == 1 || L->phase == 3 || L->phase == 4);
}

static void reference(const Loop *L, double t, double *ref, double *dref) {
    double tau;
    if (!tracked(L)) { *ref = NAN; *dref = NAN; return; }
    tau = t - L->ft0;
    if (tau < L->T) {
        *ref = L->ref0 + tau * tau * (L->ra2 + L->ra3 * tau);
        *dref = tau * (2.0 * L->ra2 + 3.0 * L->ra3 * tau);
    } else {
        *ref = L->target;
        *dref = 0.0;
    }
}

static double ctrl_rate(const Loop *L, double t, double x2, double v_wheel, double vx, double xbs) {
    const double *p = L->p;
    int ph = L->phase;
    if (L->kind == 0) {
        double r;
        if (ph == 0) return p[P_INITIAL_RATE];
        if (tracked(L)) {
            double ref, dref;
            reference(L, t, &ref, &dref);
            return (-p[P_A] / vx * xbs * x2 - dref + p[P_ALPHA] * (x2 - ref)) / p[P_B];
        }
        r = L->rates[ph];
        if (r == 0.0) return 0.0;
        return r / (v_wheel > V_WHEEL_FLOOR ? v_wheel : V_WHEEL_FLOOR);
    } else {
        double z1_ref;
        if (ph == 0) return p[P_INITIAL_RATE];
        z1_ref = ph == 1 ? p[P_Z_REF] : -p[P_Z_REF];
        return (-p[P_A] * x2 * xbs + p[P_KP] * (x2 - z1_ref)) / (vx * p[P_B]);
    }
}

/* The outgoing guards of the current phase; returns their number. */
static int ctrl_guards(const Loop *L, double x2, double xbs, double *g) {
    if (L->kind == 0) {
        int i, n = L->ng[L->phase];
        for (i = 0; i < n; ++i) g[i] = L->sgn[L->phase][i] * (x2 - L->thr[L->phase][i]);
        return n;
    }
    if (L->phase == 1) { g[0] = xbs - L->p[P_CHI_B]; return 1; }
    if (L->phase == 0) { g[0] = L->p[P_CHI_A] - xbs; g[1] = L->start - x2; return 2; }
    g[0] = L->p[P_CHI_A] - xbs;
    return 1;
}

static void five_enter(Loop *L, int ph, double t, double x2, double v_wheel) {
    const double *p = L->p;
    L->phase = ph;
    L->ft0 = t;
    L->deadline = (p[P_HAS_TIMEOUT] != 0.0 && (ph == 1 || ph == 5)) ? t + p[P_TIMEOUT] : INFINITY;
    if (tracked(L)) {
        double exit_thr = L->thr[ph][0];
        double target = exit_thr + p[P_OVERSHOOT] * (exit_thr - x2);
        double span = target - x2;
        double floor_v = V_WHEEL_FLOOR > v_wheel ? V_WHEEL_FLOOR : v_wheel;
        double open_loop = fabs(L->rates[ph]) / floor_v;
        double rate = p[P_MAX_RATE] < open_loop ? p[P_MAX_RATE] : open_loop;
        L->T = 1.5 * fabs(span) / (p[P_B] * rate);
        L->ref0 = x2;
        L->ra2 = 3.0 * span / pow(L->T, 2.0);
        L->ra3 = -2.0 * span / pow(L->T, 3.0);
        L->target = target;
    }
}

static void ctrl_fire(Loop *L, int index, double t, double x2, double v_wheel) {
    if (L->kind == 0) five_enter(L, L->nxt[L->phase][index], t, x2, v_wheel);
    else L->phase = L->phase == 1 ? 2 : 1;
}

static void ctrl_expire(Loop *L, double t, double x2, double v_wheel) {
    five_enter(L, (L->phase == 5 && x2 <= L->thr[4][0]) ? 1 : 4, t, x2, v_wheel);
}

static double ctrl_breakpoint(const Loop *L) {
    if (tracked(L)) return L->ft0 + L->T;
    return L->deadline;
}

/* ------------------------------------------------------------------ plant */
static void rhs(Loop *L, double t, const double *y, double *dy) {
    const double *p = L->p;
    double om = y[0], vx = y[1], P = y[3], R = p[P_R];
    double lam = (R * om - vx) / vx, mu, xbs, fx, omdot, ax, x2, ucmd, u;
    road_eval(L, lam, t, &mu, &xbs);
    fx = p[P_FZ] * mu;
    omdot = (-R * fx - p[P_GB] * P) / p[P_J];
    if (om <= 0.0 && omdot < 0.0) omdot = 0.0;
    ax = p[P_PRESCRIBED] != 0.0 ? -p[P_DECEL] : fx / p[P_M];
    x2 = R * omdot - ax;
    ucmd = ctrl_rate(L, t, x2, R * om, vx, L->use_hat ? L->xbs_hat : xbs);
    u = ucmd;
    if (u > p[P_MAX_RATE]) u = p[P_MAX_RATE];
    else if (u < -p[P_MAX_RATE]) u = -p[P_MAX_RATE];
    if ((P <= 0.0 && u < 0.0) || (P >= p[P_P_MAX] && u > 0.0)) u = 0.0;
    L->o_lam = lam; L->o_mu = mu; L->o_xbs = xbs; L->o_omdot = omdot; L->o_ax = ax; L->o_x2 = x2; L->o_u = u;
    dy[0] = omdot; dy[1] = ax; dy[2] = vx; dy[3] = u;
}

static void rk4_step(Loop *L, double t, const double *y, double h, const double *k1, double *out) {
    double h2 = 0.5 * h, h6, k2[NY], k3[NY], k4[NY], z[NY];
    int i;
    for (i = 0; i < NY; ++i) z[i] = y[i] + h2 * k1[i];
    rhs(L, t + h2, z, k2);
    for (i = 0; i < NY; ++i) z[i] = y[i] + h2 * k2[i];
    rhs(L, t + h2, z, k3);
    for (i = 0; i < NY; ++i) z[i] = y[i] + h * k3[i];
    rhs(L, t + h, z, k4);
    h6 = h / 6.0;
    for (i = 0; i < NY; ++i) out[i] = y[i] + h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
}

/* What a candidate event watches: guard `index` of the controller, the stop speed, or a road position. */
enum { G_CONTROLLER, G_STOP, G_ROAD };

static double guard_at(Loop *L, int what, int index, double where, double t, const double *y) {
    double g[2], dy[NY];
    if (what == G_STOP) return where - y[1];
    if (what == G_ROAD) return y[2] - where;
    rhs(L, t, y, dy);
    ctrl_guards(L, L->o_x2, L->use_hat ? L->xbs_hat : L->o_xbs, g);
    return g[index];
}

static double locate_event(Loop *L, double t, const double *y, double h, const double *k1, int what, int index,
                           double where, double g_lo, double g_hi) {
    double lo = 0.0, hi = 1.0, theta, span, g, y1[NY];
    int side = 0, it;
    for (it = 0; it < 60; ++it) {
        if ((hi - lo) * h <= 1e-10) break;
        theta = hi - g_hi * (hi - lo) / (g_hi - g_lo);
        span = hi - lo;
        {
            double a = lo + 1e-3 * span, b = hi - 1e-3 * span;
            theta = a > theta ? a : theta;
            theta = b < theta ? b : theta;
        }
        rk4_step(L, t, y, theta * h, k1, y1);
        g = guard_at(L, what, index, where, t + theta * h, y1);
        if (g > 0.0) {
            hi = theta; g_hi = g;
            if (side == 1) g_lo *= 0.5;
            side = 1;
        } else {
            lo = theta; g_lo = g;
            if (side == -1) g_hi *= 0.5;
            side = -1;
        }
    }
    return hi;
}

/* ------------------------------------------------------------------ the run */
typedef struct {
    double *rows;
    int64_t n_rows, cap_rows;
    double *events;
    int64_t n_events, cap_events;
} Record;

static int record_row(Loop *L, Record *rec, double t, const double *y) {
    double *r, ref, dref;
    if (rec == NULL) return 1;
    if (rec->n_rows >= rec->cap_rows) return 0;
    r = rec->rows + N_SERIES * rec->n_rows++;
    reference(L, t, &ref, &dref);
    r[0] = t; r[1] = y[0]; r[2] = y[1]; r[3] = y[2]; r[4] = y[3];
    r[5] = L->o_lam; r[6] = L->o_mu; r[7] = L->o_xbs; r[8] = L->o_x2; r[9] = L->o_ax; r[10] = L->o_omdot;
    r[11] = L->o_u; r[12] = (double)L->phase; r[13] = L->xbs_hat; r[14] = ref; r[15] = dref;
#ifdef RECORD_STEP
    r[16] = L->h_step;
#endif
    return 1;
}

static int record_event(Record *rec, double t, int kind, double a, double b) {
    double *e;
    if (rec == NULL) return 1;
    if (rec->n_events >= rec->cap_events) return 0;
    e = rec->events + EV_COLS * rec->n_events++;
    e[0] = t; e[1] = (double)kind; e[2] = a; e[3] = b;
    return 1;
}

#if OBS_NX > 0
static double seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ObserverXbsEstimator.update: one step with the mean of the bounding samples; 0 or the step's status. */
static int32_t observer_update(Loop *L, double *xo, const double *params, double y, double vx, double u, double dt,
                               double *fail) {
    if (dt != 0.0) {
        double sig[OBS_NS], x[OBS_NX];
        int32_t code;
        sig[0] = 0.5 * (L->est_y + y); sig[1] = 0.5 * (L->est_vx + vx); sig[2] = u;
        memcpy(x, xo, sizeof x);
        code = OBS_STEP(x, sig, params, dt);
        if (code != 0) {
            memcpy(fail + OUT_FAIL_X, xo, sizeof x);     /* the state the refused step started from */
            memcpy(fail + OUT_FAIL_SIG, sig, sizeof sig);
            fail[OUT_FAIL_DT] = dt;
            return code;
        }
        memcpy(xo, x, sizeof x);
        L->estimate = OBS_READOUT(x);
    }
    L->est_y = y; L->est_vx = vx;
    return 0;
}
#endif

#define ADD_EVENT(t, kind, a, b) do { if (!record_event(rec, t, kind, a, b)) return ST_EVENTS_FULL; } while (0)

/* The run between two steps: what switchobs_braking_run and the plant FMU (switchobs.plants.generate_plant_fmu)
 * advance.  A step is braking_advance (the integrator step with its event location and the clamp), then the
 * estimator's update (the run's, or the co-simulation master's observer), then braking_settle (the sample,
 * the road events and the controller's transitions, which read the new estimate). */
typedef struct {
    Loop L;
    double t, y[NY], k1[NY], k_end[NY], g_old[2], h, p_prev, u_mean;
    int n_old, at_break, found, found_what, found_index;
    int64_t steps;
} Braking;

static void braking_start(Braking *B, const double *p, const double *ch, int32_t n_ch) {
    Loop *L = &B->L;
    memset(B, 0, sizeof *B);
    L->p = p; L->ch = ch; L->n_ch = n_ch;
    L->a1 = L->b1 = p[P_C1]; L->a2 = L->b2 = p[P_C2]; L->a3 = L->b3 = p[P_C3];
    L->kind = (int)p[P_KIND];
    L->deadline = INFINITY;
    L->est = (int)p[P_EST];
    L->use_hat = p[P_USE_HAT] != 0.0;
    L->xbs_hat = NAN;
    L->estimate = NAN;
    if (L->kind == 0) {
        /* per phase: (sign, threshold, next phase); fires when sign * (x2 - threshold) > 0 */
        static const int nxt[6][2] = {{1, 0}, {2, 0}, {3, 4}, {4, 0}, {5, 0}, {1, 0}};
        static const int ng[6] = {1, 1, 2, 1, 1, 1};
        static const double sgn[6][2] = {{-1.0, 0.0}, {1.0, 0.0}, {1.0, -1.0}, {-1.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}};
        const double *e = p + P_EPS0;
        double thr[6][2] = {{-e[0], 0.0}, {e[1], 0.0}, {e[2], e[1]}, {e[3], 0.0}, {-e[4], 0.0}, {-e[5], 0.0}};
        memcpy(L->nxt, nxt, sizeof nxt);
        memcpy(L->ng, ng, sizeof ng);
        memcpy(L->sgn, sgn, sizeof sgn);
        memcpy(L->thr, thr, sizeof thr);
        L->rates[1] = -p[P_U1]; L->rates[3] = p[P_U3]; L->rates[4] = p[P_U4];
    } else {
        L->start = p[P_HAS_START] != 0.0 ? -p[P_START_DECEL] : -INFINITY;
    }
    B->t = 0.0;
    B->y[0] = p[P_V0] / p[P_R]; B->y[1] = p[P_V0]; B->y[2] = 0.0; B->y[3] = 0.0;
    rhs(L, B->t, B->y, B->k1);
    B->n_old = ctrl_guards(L, L->o_x2, L->use_hat ? L->xbs_hat : L->o_xbs, B->g_old);
}

/* One integrator step from B->t, ending at the first located event, at a breakpoint, or at t_limit (a
 * communication point of the plant FMU; INFINITY in the run), whichever comes first; then the clamp and the
 * step's mean pressure rate u_mean. */
static void braking_advance(Braking *B, double t_limit) {
    Loop *L = &B->L;
    const double *p = L->p;
    double y1[NY], g_new[2], h, tb, best = 2.0, t = B->t, *y = B->y;
    int n_new, i, clamped, found = -1, n_c = 0;
    /* candidates: (what, index, where, g0, g1) */
    int c_what[4], c_index[4];
    double c_where[4], c_g0[4], c_g1[4];
    const double *pending;

    h = y[1] >= p[P_V_LOW] ? p[P_DT] : p[P_DT] * y[1] / p[P_V_LOW];
    {
        double road_bp = road_breakpoint(L), kink = ctrl_breakpoint(L), bp;
        kink = kink > t + 1e-12 ? kink : INFINITY;
        bp = kink < road_bp ? kink : road_bp;
        tb = bp < p[P_T_END] ? bp : p[P_T_END];
    }
    if (t + h > t_limit + 1e-12) h = t_limit - t;
    B->at_break = t + h >= tb - 1e-12;
    if (B->at_break) h = tb - t;
    rk4_step(L, t, y, h, B->k1, y1);
    rhs(L, t + h, y1, B->k_end);
    if (p[P_LOCATABLE] != 0.0) {
        n_new = ctrl_guards(L, L->o_x2, L->use_hat ? L->xbs_hat : L->o_xbs, g_new);
        for (i = 0; i < n_new && i < B->n_old; ++i) {
            if (g_new[i] > 0.0) {
                c_what[n_c] = G_CONTROLLER; c_index[n_c] = i; c_where[n_c] = 0.0;
                c_g0[n_c] = B->g_old[i]; c_g1[n_c] = g_new[i]; ++n_c;
            }
        }
    }
    if (y1[1] <= p[P_V_STOP]) {
        c_what[n_c] = G_STOP; c_index[n_c] = 0; c_where[n_c] = p[P_V_STOP];
        c_g0[n_c] = p[P_V_STOP] - y[1]; c_g1[n_c] = p[P_V_STOP] - y1[1]; ++n_c;
    }
    pending = road_pending(L);
    if (!L->blending && pending != NULL && pending[CH_AT_TIME] == 0.0 && y1[2] >= pending[CH_WHERE]) {
        double x_change = pending[CH_WHERE];
        c_what[n_c] = G_ROAD; c_index[n_c] = 0; c_where[n_c] = x_change;
        c_g0[n_c] = y[2] - x_change; c_g1[n_c] = y1[2] - x_change; ++n_c;
    }
    for (i = 0; i < n_c; ++i) {
        double g_lo = c_g0[i] > 0.0 ? 0.0 : c_g0[i];
        double theta = locate_event(L, t, y, h, B->k1, c_what[i], c_index[i], c_where[i], g_lo, c_g1[i]);
        if (theta < best) { best = theta; found = i; }
    }
    B->found = found;
    B->found_what = found >= 0 ? c_what[found] : 0;
    B->found_index = found >= 0 ? c_index[found] : 0;
    if (found >= 0 && best < 1.0) {
        h *= best;
        B->at_break = 0;
        rk4_step(L, t, y, h, B->k1, y1);
        rhs(L, t + h, y1, B->k_end);
    }
    t += h;
    B->t = t;
    B->h = h;
    L->h_step = h;
    /* clamp: the state projected on its admissible set */
    clamped = y1[0] < 0.0 || y1[3] < 0.0 || y1[3] > p[P_P_MAX];
    y[1] = y1[1]; y[2] = y1[2];
    if (clamped) {
        double P = y1[3] < 0.0 ? 0.0 : y1[3];
        y[0] = y1[0] < 0.0 ? 0.0 : y1[0];
        y[3] = p[P_P_MAX] < P ? p[P_P_MAX] : P;
        rhs(L, t, y, B->k_end);
    } else {
        y[0] = y1[0]; y[3] = y1[3];
    }
    B->steps += 1;
    /* the estimator advances over the step with the mean pressure rate */
    B->u_mean = (y[3] - B->p_prev) / h;
    B->p_prev = y[3];
}

/* After the estimator's update: the sample, the road events, the stall timeout and the controller's
 * transitions.  Returns the run's status ST_* where it ends, else -1.  rec NULL: nothing recorded; out: where
 * a cascade is reported (OUT_CASCADE_*). */
static int braking_settle(Braking *B, Record *rec, double *out) {
    Loop *L = &B->L;
    const double *p = L->p;
    double t = B->t, *y = B->y;
    int i, changed, rounds, fired;
    const double *pending;

    if (!record_row(L, rec, t, y)) return ST_ROWS_FULL;
    changed = L->use_hat;
    if (B->found >= 0 && B->found_what == G_STOP) return ST_STOPPED;
    if (B->found >= 0 && B->found_what == G_ROAD) {
        ADD_EVENT(t, EV_ROAD_POSITION, (double)L->next, y[2]);
        road_start_change(L, t);
        changed = 1;
    }
    if (B->at_break) {
        /* _RoadState.at_breakpoint */
        pending = road_pending(L);
        if (L->blending && t >= L->t0 + L->dur - 1e-12) {
            L->a1 = L->b1; L->a2 = L->b2; L->a3 = L->b3;
            L->blending = 0;
            changed = 1;
        } else if (!L->blending && pending != NULL && pending[CH_AT_TIME] != 0.0
                   && t >= pending[CH_WHERE] - 1e-12) {
            ADD_EVENT(t, EV_ROAD_TIME, (double)L->next, 0.0);
            road_start_change(L, t);
            changed = 1;
        }
    }
    if (changed) rhs(L, t, y, B->k_end);
    /* _transitions: the stall timeout, then the located guard and the cascade */
    fired = (B->found >= 0 && B->found_what == G_CONTROLLER) ? B->found_index : -1;
    if (fired < 0 && t >= L->deadline - 1e-12) {
        int before = L->phase;
        ctrl_expire(L, t, L->o_x2, p[P_R] * y[0]);
        ADD_EVENT(t, EV_TIMEOUT, (double)before, (double)L->phase);
        rhs(L, t, y, B->k_end);
    }
    rounds = 0;
    for (;;) {
        if (fired < 0) {
            B->n_old = ctrl_guards(L, L->o_x2, L->use_hat ? L->xbs_hat : L->o_xbs, B->g_old);
            for (i = 0; i < B->n_old; ++i) {
                if (B->g_old[i] > 0.0) { fired = i; break; }
            }
            if (fired < 0) break;
        }
        rounds += 1;
        if (rounds > MAX_CASCADE) {
            out[OUT_CASCADE_INDEX] = (double)fired;
            out[OUT_CASCADE_PHASE] = (double)L->phase;
            return ST_CASCADE;
        }
        {
            int before = L->phase;
            ctrl_fire(L, fired, t, L->o_x2, p[P_R] * y[0]);
            ADD_EVENT(t, EV_PHASE, (double)before, (double)L->phase);
        }
        fired = -1;
        rhs(L, t, y, B->k_end);
    }
    memcpy(B->k1, B->k_end, sizeof B->k1);
    return t >= p[P_T_END] - 1e-12 ? ST_DURATION : -1;
}

/* One braking run.  p: parameters (P_*); ch: road changes (CH_COLS per change); xo: observer state, x[0]
 * set here to the first measurement; op: observer parameters; rows, events: output buffers; out: OUT_*.
 * Returns the status ST_*. */
int32_t switchobs_braking_run(const double *p, const double *ch, int32_t n_ch, double *xo, const double *op,
                              double *rows, int64_t cap_rows, double *events, int64_t cap_events, double *out) {
    Braking Bv, *B = &Bv;
    Loop *L = &B->L;
    Record recv, *rec = &recv;
    double obs_time = 0.0;
    int status;
    (void)xo; (void)op;

    braking_start(B, p, ch, n_ch);
    rec->rows = rows; rec->cap_rows = cap_rows; rec->n_rows = 0;
    rec->events = events; rec->cap_events = cap_events; rec->n_events = 0;
    if (L->est == 2) {
#if OBS_NX > 0
        if (p[P_OBS_MEASURED_FIRST] != 0.0) xo[0] = L->o_x2;
        L->est_y = L->o_x2; L->est_vx = B->y[1];
        L->estimate = OBS_READOUT(xo);
#endif
    }
    if (!record_row(L, rec, B->t, B->y)) { status = ST_ROWS_FULL; goto done; }
    for (;;) {
        braking_advance(B, INFINITY);
        if (L->est == 1) {
            L->xbs_hat = L->o_xbs;
        } else if (L->est == 2) {
#if OBS_NX > 0
            double t_obs = seconds();
            int32_t code = observer_update(L, xo, op, L->o_x2, B->y[1], B->u_mean, B->h, out);
            obs_time += seconds() - t_obs;
            if (code != 0) {
                status = record_row(L, rec, B->t, B->y) ? ST_OBSERVER_FAILED : ST_ROWS_FULL;
                goto done;
            }
            L->xbs_hat = L->estimate;
#endif
        }
        status = braking_settle(B, rec, out);
        if (status >= 0) break;
    }
done:
    out[OUT_T] = B->t;
    out[OUT_STEPS] = (double)B->steps;
    out[OUT_ROWS] = (double)rec->n_rows;
    out[OUT_EVENTS] = (double)rec->n_events;
    out[OUT_OBSERVER_TIME] = obs_time;
    out[OUT_ESTIMATE] = L->estimate;
    out[OUT_EST_Y] = L->est_y;
    out[OUT_EST_VX] = L->est_vx;
    return status;
}
