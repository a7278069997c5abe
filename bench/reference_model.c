/* Scalar reference of the Goodwill & Haake 2004 ball model, for bench/run.py.
 *
 * The same plain loop as tests/reference_model.py, written from docs/model.md:
 * Eq. (16) explicit central difference (dt = 0.01 ms, x(0) = 0, x(dt) = VB dt,
 * x' the backward difference); kB = kCONST = 80 kN/m on the steps with
 * t < 0.2 ms, else Eq. (4); dCONT Eq. (5); cB Eq. (7); cM Eq. (13) in
 * compression only; zero force while x < 2 mm in compression (cloth); end of
 * contact at the first step with x' <= 0 and F <= 0, interpolated linearly.
 * One impact at a time, one core: the throughput a plain compiled loop gives.
 *
 * Build and run (bench/run.py does this in a temporary directory):
 *     cc -O2 -ffp-contract=off -o reference_model bench/reference_model.c -lm
 * (-ffp-contract=off: no fused multiply-add, so the arithmetic is that of numpy's)
 *     printf '0.0577 21000 16000000 1.65 3500 3 20\n14 20 30\n' | ./reference_model
 * stdin: "mass_kg kb0_N_m ak a ac n repeats", then n inbound speeds [m/s].
 * stdout: "impacts_per_s <best of repeats>", then "tc_s cor" for each impact
 * (%.17g).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define RHO 5.212       /* shell mass per unit area [kg/m^2] */
#define K_CONST 80.0e3  /* pre-buckling stiffness [N/m] */
#define T_BUCKLE 0.2e-3 /* [s] */
#define X_CLOTH 2.0e-3  /* [m] */
#define DT 0.01e-3      /* [s] */
#define T_MAX 20.0e-3   /* [s] */

static double d_cont(double x) /* Eq. (5) [m] */
{
    if (x <= 0.0)
        return 0.0;
    return x * (7.66 + x * (-453.0 + x * (1.746e4 + x * -2.776e5))); /* Horner */
}

static void impact(double vin, double m, double kb0, double ak, double a, double ac,
                   double *tc, double *cor)
{
    const long n_buckle = lround(T_BUCKLE / DT);
    const long n_steps = (long)ceil(T_MAX / DT) + 2;
    double x_prev = 0.0, x = vin * DT, d_prev = 0.0, f_prev = 0.0, v_prev = vin;
    *tc = NAN;
    *cor = NAN;
    for (long step = 1; step < n_steps; step++) {
        double t = step * DT;
        double v = (x - x_prev) / DT;
        double d = d_cont(x);
        double k = step < n_buckle ? K_CONST : kb0 + ak * pow(x > 0.0 ? x : 0.0, a); /* Eq. (4) */
        double c_b = ac * d * d;                                                     /* Eq. (7) */
        double c_m = 0.0;
        if (v > 0.0) { /* Eq. (13), compression only */
            double m2 = RHO * M_PI * d * d / 4.0;
            c_m = m * RHO * M_PI * (d * d - d_prev * d_prev) / (4.0 * DT * (m - m2));
        }
        double f = k * x + (c_b + c_m) * v; /* Eq. (14) */
        if (v > 0.0 && x < X_CLOTH)
            f = 0.0;
        if (v <= 0.0 && f <= 0.0) {
            double frac = f_prev - f > 0.0 ? f_prev / (f_prev - f) : 1.0;
            frac = frac < 0.0 ? 0.0 : (frac > 1.0 ? 1.0 : frac);
            *tc = t - DT + frac * DT;
            *cor = -(v_prev + frac * (v - v_prev)) / vin;
            return;
        }
        double x_next = 2.0 * x - x_prev - DT * DT / m * f; /* Eq. (16) */
        x_prev = x;
        x = x_next;
        d_prev = d;
        f_prev = f;
        v_prev = v;
    }
}

int main(void)
{
    double m, kb0, ak, a, ac;
    long n, repeats;
    if (scanf("%lf %lf %lf %lf %lf %ld %ld", &m, &kb0, &ak, &a, &ac, &n, &repeats) != 7 || n < 1 || repeats < 1) {
        fprintf(stderr, "reference_model: expected 'mass_kg kb0_N_m ak a ac n repeats' on stdin\n");
        return 2;
    }
    double *vin = malloc(n * sizeof *vin), *tc = malloc(n * sizeof *tc), *cor = malloc(n * sizeof *cor);
    if (!vin || !tc || !cor)
        return 3;
    for (long i = 0; i < n; i++)
        if (scanf("%lf", &vin[i]) != 1) {
            fprintf(stderr, "reference_model: expected %ld speeds, got %ld\n", n, i);
            return 2;
        }
    double best = INFINITY;
    for (long r = 0; r < repeats; r++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
        for (long i = 0; i < n; i++)
            impact(vin[i], m, kb0, ak, a, ac, &tc[i], &cor[i]);
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
        double s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (s < best)
            best = s;
    }
    printf("impacts_per_s %.6g\n", n / best);
    for (long i = 0; i < n; i++)
        printf("%.17g %.17g\n", tc[i], cor[i]);
    free(vin);
    free(tc);
    free(cor);
    return 0;
}
