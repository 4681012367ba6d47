/* Calling a switchobs-generated observer from C.
 *
 * Reads recorded signals (t, y, vx, u, true XBS) from a CSV file, steps the 4D XBS observer of
 * seed 000 Sec. IV over each interval with the signals held at the mean of the two bounding samples
 * (u is already the interval's mean pressure rate), prints the estimate twice a second and the RMS
 * error, and writes the estimate to a second CSV file.  Build: see the Makefile.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "switchobs_abs_xbs4.h"

int main(int argc, char **argv)
{
    double xhat[SWITCHOBS_ABS_XBS4_NX] = {0.0, 0.5, 0.0, 0.0};   /* XBS estimate z2 starts at 0.5 */
    double signals[SWITCHOBS_ABS_XBS4_NS];
    double t, y, vx, u, xbs, t_prev = 0.0, y_prev = 0.0, vx_prev = 0.0, next_print = 0.0;
    double sq_error = 0.0;
    long n = 0, n_error = 0;
    int i;
    int32_t status;
    char line[512];
    FILE *in, *out;

    if (argc != 3) {
        fprintf(stderr, "usage: %s SIGNALS.csv ESTIMATE.csv\n", argv[0]);
        return 2;
    }
    in = fopen(argv[1], "r");
    out = fopen(argv[2], "w");
    if (in == NULL || out == NULL || fgets(line, (int)sizeof line, in) == NULL) {
        fprintf(stderr, "cannot read %s or write %s\n", argv[1], argv[2]);
        return 2;
    }
    fprintf(out, "t,xbs_hat,xbs\n");
    while (fgets(line, (int)sizeof line, in) != NULL) {
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf", &t, &y, &vx, &u, &xbs) != 5) {
            fprintf(stderr, "bad line: %s", line);
            return 2;
        }
        if (n == 0) {
            xhat[SWITCHOBS_ABS_XBS4_X_Z1] = y;              /* the measured state starts at y */
        } else {
            signals[SWITCHOBS_ABS_XBS4_S_Y] = 0.5 * (y_prev + y);
            signals[SWITCHOBS_ABS_XBS4_S_VX] = 0.5 * (vx_prev + vx);
            signals[SWITCHOBS_ABS_XBS4_S_U] = u;
            status = switchobs_abs_xbs4_step(xhat, signals, NULL, t - t_prev);   /* NULL: default params */
            if (status != SWITCHOBS_ABS_XBS4_OK) {
                fprintf(stderr, "t = %g: %s\n", t, switchobs_abs_xbs4_status_message(status));
                return 1;
            }
        }
        fprintf(out, "%.17g,%.17g,%.17g\n", t, xhat[SWITCHOBS_ABS_XBS4_X_Z2], xbs);
        if (t >= 0.5) {
            sq_error += (xhat[SWITCHOBS_ABS_XBS4_X_Z2] - xbs) * (xhat[SWITCHOBS_ABS_XBS4_X_Z2] - xbs);
            ++n_error;
        }
        if (t >= next_print) {
            printf("t = %5.2f s  XBS estimate %8.4f  true %8.4f\n", t, xhat[SWITCHOBS_ABS_XBS4_X_Z2], xbs);
            next_print += 0.5;
        }
        t_prev = t;
        y_prev = y;
        vx_prev = vx;
        ++n;
    }
    fclose(in);
    fclose(out);
    printf("%ld samples; RMS XBS error after 0.5 s: %.6f\n", n, n_error ? sqrt(sq_error / (double)n_error) : 0.0);
    printf("final state:");
    for (i = 0; i < SWITCHOBS_ABS_XBS4_NX; ++i) printf(" %.17g", xhat[i]);
    printf("\n");
    return 0;
}
