/* Kernels of the encoder chain: the TSA fit of _tsa.py, the three-stage estimator and the notch of
 * _three_stage.py in C.
 *
 * A port statement for statement of ThreeStageEstimator.update (stage 1 _RevolutionDetrend or _HighPass,
 * stage 2 _Rls, stage 3 the compensation) and NotchFilter.update: the same floating-point operations in
 * the same order, the system libm as Python's math (the products with the symmetric Gamma read its rows for
 * its columns: the same numbers, see sym_matvec).  The dot products and matrix-vector products are
 * summed left to right, where numpy hands them to BLAS: the three-stage outputs differ from the
 * Python reference by rounding only (tests/test_sensors_kernels.py states the tolerance); the notch is
 * bit for bit.  ISO C99 keeps floating-point contraction off (no fused multiply-add).
 *
 * cfg (read only): CFG_* below.  state: STATE_* scalars, then the detrend's ring buffers (rows: theta,
 * omega, alpha; sums: running sums of omega and alpha), then Gamma and theta of the velocity RLS, then
 * those of the acceleration RLS, then the regressors of each sample in the detrend's ring (Phi_w, Phi_a,
 * |Phi_w|^2, |Phi_a|^2: the identification of the revolution's centre sample reuses those computed when
 * it was the newest, the same function of the same numbers); switchobs/sensors/_kernels.py lays it out.
 *
 * The TSA fit (switchobs_tsa_fit) solves each window's least-squares problem by Householder QR as LAPACK's
 * dgeqr2 does (the reference _tsa._fit calls LAPACK through numpy), with the reflections applied to the
 * right-hand side instead of forming Q: the same method, its own rounding (tests/test_sensors_kernels.py
 * states the tolerance).  The window's mean time stamp is summed oldest first, as measure_edges sums it.
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
void switchobs_tsa_fit(int64_t count, const double *times, const double *angles, const int64_t *last,
                       const double *t_eval, int64_t n, int64_t m, double *work, double *out);

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

/* y = Gamma x for the symmetric Gamma: y[i] = dot(d, Gamma + i d, x), each sum over k in the same order, read
 * from row k instead of column k (Gamma[i][k] == Gamma[k][i] bit for bit: it starts diagonal, and the decay
 * and the update (gphi[i] gphi[j]) f keep each pair of mirrored entries equal), so that four sums run side
 * by side in registers (written out: the compiler's vectoriser at -O2 takes a block of four, not a loop
 * whose length it does not know). */
static void sym_matvec(int d, const double *restrict gamma, const double *restrict x, double *restrict y) {
    int i = 0;
    for (; i + 4 <= d; i += 4) {
        double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
        for (int k = 0; k < d; ++k) {
            const double *restrict g = gamma + k * d + i;
            double xk = x[k];
            a0 += g[0] * xk;
            a1 += g[1] * xk;
            a2 += g[2] * xk;
            a3 += g[3] * xk;
        }
        y[i] = a0;
        y[i + 1] = a1;
        y[i + 2] = a2;
        y[i + 3] = a3;
    }
    for (; i < d; ++i) {
        double acc = 0.0;
        for (int k = 0; k < d; ++k) acc += gamma[k * d + i] * x[k];
        y[i] = acc;
    }
}

/* gamma[i][j] = gamma[i][j] - (a[i] a[j]) f, four entries at a time as sym_matvec */
static void rank_one_down(int d, double *restrict gamma, const double *restrict a, double f) {
    for (int r = 0; r < d; ++r) {
        double *restrict row = gamma + r * d;
        double ar = a[r];
        int j;
        for (j = 0; j + 4 <= d; j += 4) {
            row[j] = row[j] - (ar * a[j]) * f;
            row[j + 1] = row[j + 1] - (ar * a[j + 1]) * f;
            row[j + 2] = row[j + 2] - (ar * a[j + 2]) * f;
            row[j + 3] = row[j + 3] - (ar * a[j + 3]) * f;
        }
        for (; j < d; ++j) row[j] = row[j] - (ar * a[j]) * f;
    }
}

/* _Rls.step on Gamma (d x d, row major) and theta */
static void rls_step(const double *cfg, int d, double *gamma, double *theta, const double *phi, double phi_sq,
                     double zeta) {
    double gphi[MAX_DIM], gp[MAX_DIM];
    double w = cfg[CFG_DT] / (1.0 + cfg[CFG_KAPPA] * phi_sq);
    double decay = cfg[CFG_DECAY];       /* read once: gamma might alias cfg, as far as the compiler knows */
    int i = 0;
    for (; i + 4 <= d * d; i += 4) {
        gamma[i] *= decay;
        gamma[i + 1] *= decay;
        gamma[i + 2] *= decay;
        gamma[i + 3] *= decay;
    }
    for (; i < d * d; ++i) gamma[i] *= decay;
    sym_matvec(d, gamma, phi, gphi);
    double f = w / (1.0 + w * dot(d, phi, gphi));
    rank_one_down(d, gamma, gphi, f);
    double err = dot(d, phi, theta) - zeta;
    sym_matvec(d, gamma, phi, gp);
    double we = w * err;
    for (i = 0; i < d; ++i) theta[i] -= gp[i] * we;
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

/* _RevolutionDetrend.__call__: 1 and (theta, omega, alpha, zeta_omega, zeta_alpha, centre) of the centre, or 0 */
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
    out[5] = (double)(centre % size);
    return 1;
}

/* ThreeStageEstimator.update: out = (omega_r_hat, alpha_r_hat); 1 (nothing done) for more harmonics than
   the buffers hold */
int switchobs_three_stage_update(const double *cfg, double *state, double theta, double omega, double alpha,
                                 double *out) {
    int d = 2 * (int)cfg[CFG_M];
    int64_t size = (int64_t)cfg[CFG_SIZE];
    double *gw = state + ST_HEAD + 5 * size, *tw = gw + d * d, *ga = tw + d, *ta = ga + d * d;
    double *cache = ta + d, local[2 * MAX_DIM + 2];
    if (d > MAX_DIM) return 1;
    /* this sample's regressors, in the ring slot the detrend gives it (highpass: no ring) */
    double *pw = size > 0 ? cache + (((int64_t)state[ST_K] + 1) % size) * (2 * d + 2) : local, *pa = pw + d;
    regressors(cfg, theta, omega, alpha, pw, pa, pa + d, pa + d + 1);
    if (cfg[CFG_HIGHPASS] != 0.0) {
        rls_step(cfg, d, gw, tw, pw, pa[d], highpass(cfg, state + ST_HPW_ON, omega));
        rls_step(cfg, d, ga, ta, pa, pa[d + 1], highpass(cfg, state + ST_HPA_ON, alpha));
    } else {
        double c[6];
        if (detrend(cfg, state, theta, omega, alpha, c)) {
            const double *cw = cache + (int64_t)c[5] * (2 * d + 2), *ca = cw + d;
            rls_step(cfg, d, gw, tw, cw, ca[d], c[3]);
            rls_step(cfg, d, ga, ta, ca, ca[d + 1], c[4]);
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

/* p(x) = c[0] + c[1] x + ... + c[deg] x^deg by Horner's rule */
static double horner(const double *c, int64_t deg, double x) {
    double acc = c[deg];
    for (int64_t k = deg - 1; k >= 0; --k) acc = acc * x + c[k];
    return acc;
}

/* The fit of one window (n times tw, angles thw): the coefficients p of the order-m polynomial in
 * s = (t - tw[0]) / span fitted to theta - thw[0], by Householder QR.  a and y: work (n * (m + 1), n). */
static void fit_window(const double *tw, const double *thw, int64_t n, int64_t m, double span, double *a,
                       double *y, double *p) {
    int64_t cols = m + 1;
    double t0 = tw[0];
    for (int64_t j = 0; j < n; ++j) {          /* a: column major, n x cols */
        double s = (tw[j] - t0) / span, power = 1.0;
        for (int64_t k = 0; k < cols; ++k) {
            a[k * n + j] = power;
            power *= s;
        }
        y[j] = thw[j] - thw[0];
    }
    /* Householder QR, column by column: H = I - tau v v^T with v[k] = 1 maps a[k.., k] onto beta e_k */
    for (int64_t k = 0; k < cols; ++k) {
        double *ak = a + k * n;
        double xnorm2 = 0.0;
        for (int64_t j = k + 1; j < n; ++j) xnorm2 += ak[j] * ak[j];
        double alpha0 = ak[k];
        if (xnorm2 == 0.0) continue;       /* already triangular in this column: H = I */
        double beta = sqrt(alpha0 * alpha0 + xnorm2);
        if (alpha0 > 0.0) beta = -beta;
        double tau = (beta - alpha0) / beta, scale = 1.0 / (alpha0 - beta);
        for (int64_t j = k + 1; j < n; ++j) ak[j] *= scale;
        ak[k] = beta;
        for (int64_t c = k + 1; c <= cols; ++c) {     /* the later columns, then y (c == cols) */
            double *ac = c < cols ? a + c * n : y;
            double w = ac[k];
            for (int64_t j = k + 1; j < n; ++j) w += ak[j] * ac[j];
            w *= tau;
            ac[k] -= w;
            for (int64_t j = k + 1; j < n; ++j) ac[j] -= w * ak[j];
        }
    }
    for (int64_t k = cols - 1; k >= 0; --k) {       /* R p = (Q^T y)[0 .. m] */
        double acc = y[k];
        for (int64_t c = k + 1; c < cols; ++c) acc -= a[c * n + k] * p[c];
        p[k] = acc / a[k * n + k];
    }
}

/* _tsa._fit over count windows: window i holds the n events last[i] - n + 1 .. last[i]; the order-m
 * polynomial in s = (t - t0) / span is fitted to theta - theta0 (seed 001 (5.2)-(5.3), Appendix C) and it
 * and its derivatives are evaluated at t_eval[i] (5.4)-(5.5).  out (4 x count, row major): theta, omega,
 * alpha and the window's mean time stamp.  work: n * (m + 2) + 2 * (m + 1) doubles.  A sample whose window
 * is the previous sample's (no edge in between: at 1 kHz and a few hundred edges a second, every other
 * sample or so) reuses its fit: the same numbers, evaluated at its own time. */
void switchobs_tsa_fit(int64_t count, const double *times, const double *angles, const int64_t *last,
                       const double *t_eval, int64_t n, int64_t m, double *work, double *out) {
    int64_t cols = m + 1;
    double *a = work, *y = work + n * cols, *p = y + n, *dp = p + cols;
    double span = 0.0, total = 0.0;
    for (int64_t i = 0; i < count; ++i) {
        const double *tw = times + last[i] - n + 1, *thw = angles + last[i] - n + 1;
        if (i == 0 || last[i] != last[i - 1]) {
            span = tw[n - 1] - tw[0];
            total = 0.0;
            for (int64_t j = 0; j < n; ++j) total += tw[j];
            fit_window(tw, thw, n, m, span, a, y, p);
        }
        double se = (t_eval[i] - tw[0]) / span;
        for (int64_t k = 1; k < cols; ++k) dp[k - 1] = p[k] * (double)k;
        out[i] = thw[0] + horner(p, m, se);
        out[count + i] = horner(dp, m - 1, se) / span;
        for (int64_t k = 1; k < m; ++k) dp[k - 1] = dp[k] * (double)k;
        out[2 * count + i] = horner(dp, m - 2, se) / (span * span);
        out[3 * count + i] = total / (double)n;
    }
}
