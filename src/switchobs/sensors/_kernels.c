/* Kernels of the encoder chain: the three-stage estimator and the notch of _three_stage.py in C.
 *
 * A port statement for statement of ThreeStageEstimator.update (stage 1 _RevolutionDetrend or _HighPass,
 * stage 2 _Rls, stage 3 the compensation) and NotchFilter.update: the same floating-point operations in
 * the same order, the system libm as Python's math.  The dot products and matrix-vector products are
 * summed left to right, where numpy hands them to BLAS: the three-stage outputs differ from the
 * Python reference by rounding only (tests/test_sensors_kernels.py states the tolerance); the notch is
 * bit for bit.  ISO C99 keeps floating-point contraction off (no fused multiply-add).
 *
 * cfg (read only): CFG_* below.  state: STATE_* scalars, then the detrend's ring buffers (rows: theta,
 * omega, alpha; sums: running sums of omega and alpha), then Gamma and theta of the velocity RLS, then
 * those of the acceleration RLS; switchobs/sensors/_kernels.py lays it out.
 */
#include <math.h>
#include <stdint.h>

#define PI 3.14159265358979323846
/* 2 * MAX_HARMONICS of _three_stage.py */
#define MAX_DIM 400

enum { CFG_M, CFG_DT, CFG_KAPPA, CFG_DECAY, CFG_SIGMA2, CFG_SIGMA4, CFG_CURVATURE, CFG_SIZE, CFG_HIGHPASS, CFG_HP_A };
enum { ST_K, ST_HPW_ON, ST_HPW_X, ST_HPW_Y, ST_HPA_ON, ST_HPA_X, ST_HPA_Y, ST_HEAD };

int switchobs_three_stage_run(const double *cfg, double *state, int64_t n, const double *theta,
                              const double *omega, const double *alpha, double *out_omega, double *out_alpha);
int switchobs_three_stage_update(const double *cfg, double *state, double theta, double omega, double alpha,
                                 double *out);
void switchobs_notch_run(double *state, double dt, double damping, int64_t n, const double *u,
                         const double *centre, double *out);

/* (Phi_w, Phi_a, |Phi_w|^2, |Phi_a|^2): ThreeStageEstimator.regressors */
static void regressors(const double *cfg, double th, double om, double al, double *pw, double *pa, double *nw,
                       double *na) {
    int m = (int)cfg[CFG_M];
    double w2 = om * om;
    for (int i = 0; i < m; ++i) {
        double k = (double)(i + 1);
        double kt = k * th;
        double c = cos(kt), s = sin(kt);
        double dc = c * k, ds = -s * k, k2 = k * k;
        pw[2 * i] = dc * om;
        pw[2 * i + 1] = ds * om;
        pa[2 * i] = dc * al - (s * k2) * w2;
        pa[2 * i + 1] = ds * al - (c * k2) * w2;
    }
    *nw = cfg[CFG_SIGMA2] * w2;
    *na = cfg[CFG_SIGMA2] * al * al + cfg[CFG_SIGMA4] * w2 * w2;
}

static double dot(int d, const double *a, const double *b) {
    double acc = 0.0;
    for (int i = 0; i < d; ++i) acc += a[i] * b[i];
    return acc;
}

/* _Rls.step on Gamma (d x d, row major) and theta */
static void rls_step(const double *cfg, int d, double *gamma, double *theta, const double *phi, double phi_sq,
                     double zeta) {
    double gphi[MAX_DIM], gp[MAX_DIM];
    double w = cfg[CFG_DT] / (1.0 + cfg[CFG_KAPPA] * phi_sq);
    for (int i = 0; i < d * d; ++i) gamma[i] *= cfg[CFG_DECAY];
    for (int i = 0; i < d; ++i) gphi[i] = dot(d, gamma + i * d, phi);
    double f = w / (1.0 + w * dot(d, phi, gphi));
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) gamma[i * d + j] = gamma[i * d + j] - (gphi[i] * gphi[j]) * f;
    double err = dot(d, phi, theta) - zeta;
    for (int i = 0; i < d; ++i) gp[i] = dot(d, gamma + i * d, phi);
    double we = w * err;
    for (int i = 0; i < d; ++i) theta[i] -= gp[i] * we;
}

/* _HighPass.__call__ on (on, x, y) */
static double highpass(const double *cfg, double *hp, double x) {
    hp[2] = hp[0] == 0.0 ? 0.0 : cfg[CFG_HP_A] * (hp[2] + x - hp[1]);
    hp[0] = 1.0;
    hp[1] = x;
    return hp[2];
}

/* the running sum of the samples up to x: integral() of _RevolutionDetrend.__call__ */
static void integral(const double *rows, const double *sums, int64_t size, double x, double *out) {
    double jf = floor(x - 0.5);
    int64_t j = (int64_t)jf;
    double frac = x - 0.5 - jf;
    const double *s = sums + 2 * (j % size), *r = rows + 3 * ((j + 1) % size);
    out[0] = s[0] + frac * r[1];
    out[1] = s[1] + frac * r[2];
}

/* _RevolutionDetrend.__call__: 1 and (theta, omega, alpha, zeta_omega, zeta_alpha) of the centre, or 0 */
static int detrend(const double *cfg, double *state, double th, double om, double al, double *out) {
    int64_t size = (int64_t)cfg[CFG_SIZE];
    double *rows = state + ST_HEAD, *sums = rows + 3 * size;
    int64_t k = (int64_t)state[ST_K] + 1;
    state[ST_K] = (double)k;
    double *row = rows + 3 * (k % size), *sum = sums + 2 * (k % size);
    row[0] = th;
    row[1] = om;
    row[2] = al;
    if (k) {
        const double *prev = sums + 2 * ((k - 1) % size);
        sum[0] = prev[0] + om;
        sum[1] = prev[1] + al;
    } else {
        sum[0] = om;
        sum[1] = al;
    }
    if (om == 0.0) return 0;
    double half = PI / (fabs(om) * cfg[CFG_DT]);
    double span = ceil(2.0 * half + 0.5);
    /* a centre before the first sample (or a speed so small that the span overflows) is never available */
    if (!(span <= (double)k)) return 0;
    int64_t centre = k - (int64_t)span;
    int64_t first = k - size + 1 > 0 ? k - size + 1 : 0;
    double c = (double)centre;
    if (c - 2.0 * half - 1.5 < (double)first) return 0;
    double a[2], b[2], p[2], q[2];
    integral(rows, sums, size, c + half, a);
    integral(rows, sums, size, c - half, b);
    integral(rows, sums, size, c + 2.0 * half, p);
    integral(rows, sums, size, c - 2.0 * half, q);
    double one0 = (a[0] - b[0]) / (2.0 * half), one1 = (a[1] - b[1]) / (2.0 * half);
    double two0 = (p[0] - q[0]) / (4.0 * half), two1 = (p[1] - q[1]) / (4.0 * half);
    const double *mid = rows + 3 * (centre % size);
    if (fabs(one0 - two0) > cfg[CFG_CURVATURE] * fabs(om)) return 0;
    out[0] = mid[0];
    out[1] = mid[1];
    out[2] = mid[2];
    out[3] = mid[1] - (4.0 * one0 - two0) / 3.0;
    out[4] = mid[2] - (4.0 * one1 - two1) / 3.0;
    return 1;
}

/* ThreeStageEstimator.update: out = (omega_r_hat, alpha_r_hat); 1 (nothing done) for more harmonics than
   the buffers hold */
int switchobs_three_stage_update(const double *cfg, double *state, double theta, double omega, double alpha,
                                 double *out) {
    int d = 2 * (int)cfg[CFG_M];
    int64_t size = (int64_t)cfg[CFG_SIZE];
    double *gw = state + ST_HEAD + 5 * size, *tw = gw + d * d, *ga = tw + d, *ta = ga + d * d;
    double pw[MAX_DIM], pa[MAX_DIM], nw, na;
    if (d > MAX_DIM) return 1;
    regressors(cfg, theta, omega, alpha, pw, pa, &nw, &na);
    if (cfg[CFG_HIGHPASS] != 0.0) {
        rls_step(cfg, d, gw, tw, pw, nw, highpass(cfg, state + ST_HPW_ON, omega));
        rls_step(cfg, d, ga, ta, pa, na, highpass(cfg, state + ST_HPA_ON, alpha));
    } else {
        double c[5];
        if (detrend(cfg, state, theta, omega, alpha, c)) {
            double cw[MAX_DIM], ca[MAX_DIM], cnw, cna;
            regressors(cfg, c[0], c[1], c[2], cw, ca, &cnw, &cna);
            rls_step(cfg, d, gw, tw, cw, cnw, c[3]);
            rls_step(cfg, d, ga, ta, ca, cna, c[4]);
        }
    }
    out[0] = omega - dot(d, pw, tw);
    out[1] = alpha - dot(d, pa, ta);
    return 0;
}

/* n samples through switchobs_three_stage_update */
int switchobs_three_stage_run(const double *cfg, double *state, int64_t n, const double *theta,
                              const double *omega, const double *alpha, double *out_omega, double *out_alpha) {
    for (int64_t i = 0; i < n; ++i) {
        double out[2];
        if (switchobs_three_stage_update(cfg, state, theta[i], omega[i], alpha[i], out)) return 1;
        out_omega[i] = out[0];
        out_alpha[i] = out[1];
    }
    return 0;
}

/* NotchFilter.update over n samples; state = (started, z1, z2, u_prev) */
void switchobs_notch_run(double *state, double dt, double damping, int64_t n, const double *u,
                         const double *centre, double *out) {
    double xi2 = 2.0 * damping;
    for (int64_t i = 0; i < n; ++i) {
        double arg = fabs(centre[i]) * dt / 2.0;
        double g = tan(1.5 < arg ? 1.5 : arg);
        if (state[0] == 0.0) {
            state[0] = 1.0;
            state[1] = u[i];
            state[2] = 0.0;
            state[3] = u[i];
        }
        double r1 = state[1] + g * state[2];
        double r2 = state[2] + g * (state[3] + u[i] - state[1] - xi2 * state[2]);
        double det = 1.0 + xi2 * g + g * g;
        state[1] = ((1.0 + xi2 * g) * r1 + g * r2) / det;
        state[2] = (r2 - g * r1) / det;
        state[3] = u[i];
        out[i] = u[i] - xi2 * state[2];
    }
}
