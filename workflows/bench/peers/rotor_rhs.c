/* The scaled right-hand sides of rotorsweep.kernels.models.rigid_preloaded (ball sums, law
   "ball_sum") and of the series rotors symmetric4 / asymmetric5 (cubic series law) in plain C,
   with their variational derivatives [f, J Phi] (J = [[0, I], [A, B]]: the upper rows of J Phi
   are the lower rows of Phi, as the kernels' tangent product). Parameter vectors: the kernels'
   (rigid_preloaded.P_*, series_rotor.p_layout). Compiled and run by
   workflows/bench/peers/rotor_c.py:

       rotor_floor MODEL DATA PASSES [OUT]

   MODEL: rigid_preloaded, symmetric4 or asymmetric5. DATA: int64 n_states, int64 n_params,
   n_params doubles p, n_states taus, n_states x n states, n x n doubles Phi (the tangent
   matrix of every variational evaluation). Prints "ns_rhs sum_rhs ns_var sum_var" (best of
   PASSES passes over all states); with OUT, writes every state's f (n doubles) and then every
   state's [f, J Phi] (n + n^2 doubles) there. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define NMAX 10

/* ---- rigid_preloaded: parameter offsets (rigid_preloaded.P_*) ---- */
enum { P_GAIN = 0, P_DAMP = 25, P_CONST = 50, P_UCOS = 55, P_USIN = 60, P_SUP = 65, P_WU = 70, P_WS,
       P_OFFSET, P_COS_A, P_SIN_A, P_NBALLS, P_COS_D, P_SIN_D };

/* One bearing's ball sum at journal (x, y), axial shift z: f[0..2] forces; with stiffness,
   f[3..8] = kxx kxy kyy kxz kyz kzz. Balls at fixed angles 2 pi k / N, by rotation. */
static inline void ball_sum(double x, double y, double z, const double *p, int stiffness, double *f) {
    const double e = p[P_OFFSET], ca = p[P_COS_A], sa = p[P_SIN_A], cd = p[P_COS_D], sd = p[P_SIN_D];
    const int n = (int)p[P_NBALLS];
    double c = 1.0, s = 0.0;
    for (int k = 0; k < 9; k++) f[k] = 0.0;
    for (int j = 0; j < n; j++) {
        double delta = (x * c + y * s) * ca + z * sa + e;
        if (delta > 0.0) {
            double root = sqrt(delta), q = delta * root, ux = c * ca, uy = s * ca;
            f[0] += q * ux; f[1] += q * uy; f[2] += q * sa;
            if (stiffness) {
                double dq = 1.5 * root;
                f[3] += dq * ux * ux; f[4] += dq * ux * uy; f[5] += dq * uy * uy;
                f[6] += dq * ux * sa; f[7] += dq * uy * sa; f[8] += dq * sa * sa;
            }
        }
        double c2 = c * cd - s * sd;
        s = s * cd + c * sd;
        c = c2;
    }
}

static inline void rigid_accelerations(double tau, const double *u, const double *p, const double *fa,
                                       const double *fb, double *du) {
    const double cu = cos(p[P_WU] * tau), su = sin(p[P_WU] * tau), ss = sin(p[P_WS] * tau);
    const double F[5] = {fa[0], fa[1], fb[0], fb[1], fa[2] - fb[2]};
    for (int i = 0; i < 5; i++) du[i] = u[5 + i];
    for (int i = 0; i < 5; i++) {
        double acc = p[P_CONST + i] + p[P_UCOS + i] * cu + p[P_USIN + i] * su + p[P_SUP + i] * ss;
        for (int j = 0; j < 5; j++) acc -= p[P_GAIN + 5 * i + j] * F[j] + p[P_DAMP + 5 * i + j] * u[5 + j];
        du[5 + i] = acc;
    }
}

static void rigid_rhs(double tau, const double *u, const double *p, double *du) {
    double fa[9], fb[9];
    ball_sum(u[0], u[1], u[4], p, 0, fa);
    ball_sum(u[2], u[3], -u[4], p, 0, fb);
    rigid_accelerations(tau, u, p, fa, fb, du);
}

/* Columns of dP/dq (q = x1 y1 x2 y2 z) from the two bearings' stiffness: B sees -z. */
static inline void stiffness_columns(const double *a, const double *b, int n, double K[5][5]) {
    const double cols[5][5] = {{a[3], a[4], 0.0, 0.0, a[6]}, {a[4], a[5], 0.0, 0.0, a[7]},
                               {0.0, 0.0, b[3], b[4], -b[6]}, {0.0, 0.0, b[4], b[5], -b[7]},
                               {a[6], a[7], -b[6], -b[7], a[8] + b[8]}};
    for (int j = 0; j < n; j++)
        for (int k = 0; k < n; k++) K[k][j] = cols[j][k];   /* K[row k][column j] */
}

/* dz[n:] = J Phi with J = [[0, I], [A, B]], A = -gain dP/dq, B = -damp. */
static inline void tangent(int npos, const double *gain, const double *damp, double K[5][5], const double *z,
                           double *dz) {
    const int n = 2 * npos;
    const double *phi = z + n;
    double *out = dz + n;
    double A[5][5];
    for (int i = 0; i < npos; i++)
        for (int j = 0; j < npos; j++) {
            double v = 0.0;
            for (int k = 0; k < npos; k++) v += gain[npos * i + k] * K[k][j];
            A[i][j] = -v;
        }
    memcpy(out, phi + npos * n, sizeof(double) * npos * n);
    for (int i = 0; i < npos; i++)
        for (int j = 0; j < n; j++) {
            double acc = 0.0;
            for (int k = 0; k < npos; k++) acc += A[i][k] * phi[k * n + j] - damp[npos * i + k] * phi[(npos + k) * n + j];
            out[(npos + i) * n + j] = acc;
        }
}

static void rigid_var(double tau, const double *z, const double *p, double *dz) {
    double fa[9], fb[9], K[5][5];
    ball_sum(z[0], z[1], z[4], p, 1, fa);
    ball_sum(z[2], z[3], -z[4], p, 1, fb);
    rigid_accelerations(tau, z, p, fa, fb, dz);
    stiffness_columns(fa, fb, 5, K);
    tangent(5, p + P_GAIN, p + P_DAMP, K, z, dz);
}

/* ---- the series rotors: gain (n x n), gyro (n x n), then c_r, c_a, z0, tan^2 a ---- */

/* series_rotor's cubic_load: forces and stiffness of one bearing, ring_load's layout. */
static inline void cubic_load(double x, double y, double z, const double *law, double *f) {
    const double radial = law[0], axial = law[1], z0 = law[2], tan2 = law[3];
    const double h = 0.5 / z0, e = 0.125 / (z0 * z0), a = e / (4.0 * tan2);
    const double r2 = x * x + y * y, rf = 1.0 + h * z - a * r2 - e * z * z;
    f[0] = radial * x * rf;
    f[1] = radial * y * rf;
    f[2] = axial * (z0 / 1.5 + z + 0.5 * h * z * z - e * z * z * z / 3.0) + radial * r2 * (0.5 * h - e * z);
    f[3] = radial * (rf - 2.0 * a * x * x);
    f[4] = -2.0 * radial * a * x * y;
    f[5] = radial * (rf - 2.0 * a * y * y);
    f[6] = radial * x * (h - 2.0 * e * z);
    f[7] = radial * y * (h - 2.0 * e * z);
    f[8] = axial * (1.0 + h * z - e * z * z) - radial * r2 * e;
}

static inline void series_rhs_n(int npos, const double *u, const double *p, double *fa, double *fb, double *du) {
    const double *gain = p, *gyro = p + npos * npos, *law = p + 2 * npos * npos;
    const double z = npos == 5 ? u[4] : 0.0;
    cubic_load(u[0], u[1], z, law, fa);
    cubic_load(u[2], u[3], -z, law, fb);
    const double F[5] = {fa[0], fa[1], fb[0], fb[1], fa[2] - fb[2]};
    for (int i = 0; i < npos; i++) du[i] = u[npos + i];
    for (int i = 0; i < npos; i++) {
        double acc = 0.0;
        for (int j = 0; j < npos; j++) acc -= gain[npos * i + j] * F[j] + gyro[npos * i + j] * u[npos + j];
        du[npos + i] = acc;
    }
}

static void symmetric4_rhs(double tau, const double *u, const double *p, double *du) {
    double fa[9], fb[9];
    (void)tau;
    series_rhs_n(4, u, p, fa, fb, du);
}

static void asymmetric5_rhs(double tau, const double *u, const double *p, double *du) {
    double fa[9], fb[9];
    (void)tau;
    series_rhs_n(5, u, p, fa, fb, du);
}

static inline void series_var_n(int npos, const double *z, const double *p, double *dz) {
    double fa[9], fb[9], K[5][5];
    series_rhs_n(npos, z, p, fa, fb, dz);
    stiffness_columns(fa, fb, npos, K);
    tangent(npos, p, p + npos * npos, K, z, dz);
}

static void symmetric4_var(double tau, const double *z, const double *p, double *dz) {
    (void)tau;
    series_var_n(4, z, p, dz);
}

static void asymmetric5_var(double tau, const double *z, const double *p, double *dz) {
    (void)tau;
    series_var_n(5, z, p, dz);
}

/* ---- harness ---- */

typedef void (*fn_t)(double, const double *, const double *, double *);

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int model_of(const char *name, fn_t *rhs, fn_t *var, int *n) {
    if (!strcmp(name, "rigid_preloaded")) { *rhs = rigid_rhs; *var = rigid_var; *n = 10; return 0; }
    if (!strcmp(name, "symmetric4")) { *rhs = symmetric4_rhs; *var = symmetric4_var; *n = 8; return 0; }
    if (!strcmp(name, "asymmetric5")) { *rhs = asymmetric5_rhs; *var = asymmetric5_var; *n = 10; return 0; }
    return 1;
}

int main(int argc, char **argv) {
    fn_t rhs, var;
    int n;
    if (argc < 4 || model_of(argv[1], &rhs, &var, &n)) return 2;
    FILE *f = fopen(argv[2], "rb");
    if (!f) return 3;
    long long ns, np;
    if (fread(&ns, sizeof ns, 1, f) != 1 || fread(&np, sizeof np, 1, f) != 1) return 4;
    const int m = n + n * n;
    double *p = malloc(np * sizeof(double)), *taus = malloc(ns * sizeof(double));
    double *states = malloc(ns * n * sizeof(double)), *z = malloc(m * sizeof(double));
    double *du = malloc(m * sizeof(double)), *dz = malloc(m * sizeof(double));
    if (fread(p, sizeof(double), np, f) != (size_t)np || fread(taus, sizeof(double), ns, f) != (size_t)ns
        || fread(states, sizeof(double), ns * n, f) != (size_t)(ns * n)
        || fread(z + n, sizeof(double), n * n, f) != (size_t)(n * n)) return 4;
    fclose(f);
    const int passes = atoi(argv[3]);
    double best_rhs = 1e30, best_var = 1e30, sum_rhs = 0.0, sum_var = 0.0;
    for (int r = 0; r < passes; r++) {
        double acc = 0.0, t0 = now();
        for (long long i = 0; i < ns; i++) {
            rhs(taus[i], states + n * i, p, du);
            acc += du[n / 2] + du[n - 1];
        }
        double dt = now() - t0;
        if (dt < best_rhs) best_rhs = dt;
        sum_rhs = acc;
    }
    for (int r = 0; r < passes; r++) {
        double acc = 0.0, t0 = now();
        for (long long i = 0; i < ns; i++) {
            memcpy(z, states + n * i, sizeof(double) * n);
            var(taus[i], z, p, dz);
            for (int k = n / 2; k < m; k++) acc += dz[k];
        }
        double dt = now() - t0;
        if (dt < best_var) best_var = dt;
        sum_var = acc;
    }
    printf("%.6f %.17g %.6f %.17g\n", best_rhs / ns * 1e9, sum_rhs, best_var / ns * 1e9, sum_var);
    if (argc > 4) {
        FILE *o = fopen(argv[4], "wb");
        if (!o) return 5;
        for (long long i = 0; i < ns; i++) {
            rhs(taus[i], states + n * i, p, du);
            fwrite(du, sizeof(double), n, o);
        }
        for (long long i = 0; i < ns; i++) {
            memcpy(z, states + n * i, sizeof(double) * n);
            var(taus[i], z, p, dz);
            fwrite(dz, sizeof(double), m, o);
        }
        fclose(o);
    }
    return 0;
}
