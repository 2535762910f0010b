/* The scaled right-hand side of rotorsweep.kernels.models.jeffcott_rhs in plain C: 9-ball Hertz sum,
   the other balls' angles by rotation (two trig calls per evaluation), as in contact.ring_load.
   Compiled and run by workflows/bench/peers/jeffcott_c.py. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* p: damp gain offset load cos_a sin_a n_balls phi0 cage cos_d sin_d (the kernels' parameter
   vector of jeffcott_clearance, in its order) */
static void rhs(double tau, const double *u, const double *p, double *du) {
    const double two_pi = 6.283185307179586;
    double theta = p[7] + p[8] * two_pi * tau / p[6];
    double c = cos(theta), s = sin(theta);
    const double ca = p[4], e = p[2], cd = p[9], sd = p[10];
    const int n = (int)p[6];
    double fx = 0.0, fy = 0.0;
    for (int j = 0; j < n; j++) {
        double delta = (u[0] * c + u[1] * s) * ca + e;
        if (delta > 0.0) {
            double q = delta * sqrt(delta);
            fx += q * (c * ca);
            fy += q * (s * ca);
        }
        double c2 = c * cd - s * sd;
        s = s * cd + c * sd;
        c = c2;
    }
    du[0] = u[2];
    du[1] = u[3];
    du[2] = -p[0] * u[2] - p[1] * fx;
    du[3] = -p[0] * u[3] - p[1] * fy - p[3];
}

/* The variational derivative [f(u), J(u) Phi] (20 components), forces and stiffness in one sum. */
static void var_derivative(double tau, const double *z, const double *p, double *dz) {
    const double two_pi = 6.283185307179586;
    double theta = p[7] + p[8] * two_pi * tau / p[6];
    double c = cos(theta), s = sin(theta);
    const double ca = p[4], e = p[2], cd = p[9], sd = p[10];
    const int n = (int)p[6];
    double fx = 0.0, fy = 0.0, kxx = 0.0, kxy = 0.0, kyy = 0.0;
    for (int j = 0; j < n; j++) {
        double delta = (z[0] * c + z[1] * s) * ca + e;
        if (delta > 0.0) {
            double root = sqrt(delta), q = delta * root, dq = 1.5 * root;
            double ux = c * ca, uy = s * ca;
            fx += q * ux; fy += q * uy;
            kxx += dq * ux * ux; kxy += dq * ux * uy; kyy += dq * uy * uy;
        }
        double c2 = c * cd - s * sd;
        s = s * cd + c * sd;
        c = c2;
    }
    const double g = p[1], a = p[0];
    dz[0] = z[2];
    dz[1] = z[3];
    dz[2] = -a * z[2] - g * fx;
    dz[3] = -a * z[3] - g * fy - p[3];
    double J[4][4] = {{0, 0, 1, 0}, {0, 0, 0, 1}, {-g * kxx, -g * kxy, -a, 0}, {-g * kxy, -g * kyy, 0, -a}};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double acc = 0.0;
            for (int k = 0; k < 4; k++) acc += J[i][k] * z[4 + 4 * k + j];
            dz[4 + 4 * i + j] = acc;
        }
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc < 3) return 2;
    FILE *f = fopen(argv[1], "rb");
    if (!f) return 3;
    long long n;
    double p[11];
    if (fread(&n, sizeof n, 1, f) != 1 || fread(p, sizeof(double), 11, f) != 11) return 4;
    double *taus = malloc(n * sizeof(double)), *states = malloc(4 * n * sizeof(double));
    if (fread(taus, sizeof(double), n, f) != (size_t)n) return 4;
    if (fread(states, sizeof(double), 4 * n, f) != (size_t)(4 * n)) return 4;
    fclose(f);
    int passes = atoi(argv[2]);
    double best_rhs = 1e30, best_var = 1e30, sum_rhs = 0.0, sum_var = 0.0, du[4], z[20], dz[20];
    for (int r = 0; r < passes; r++) {
        double acc = 0.0, t0 = now();
        for (long long i = 0; i < n; i++) {
            rhs(taus[i], states + 4 * i, p, du);
            acc += du[2] + du[3];
        }
        double dt = now() - t0;
        if (dt < best_rhs) best_rhs = dt;
        sum_rhs = acc;
    }
    for (int k = 0; k < 20; k++) z[k] = 0.0;
    for (int k = 0; k < 4; k++) z[4 + 5 * k] = 1.0;
    for (int r = 0; r < passes; r++) {
        double acc = 0.0, t0 = now();
        for (long long i = 0; i < n; i++) {
            for (int k = 0; k < 4; k++) z[k] = states[4 * i + k];
            var_derivative(taus[i], z, p, dz);
            for (int k = 2; k < 20; k++) acc += dz[k];
        }
        double dt = now() - t0;
        if (dt < best_var) best_var = dt;
        sum_var = acc;
    }
    printf("%.6f %.17g %.6f %.17g\n", best_rhs / n * 1e9, sum_rhs, best_var / n * 1e9, sum_var);
    return 0;
}
