/* Reads rows "t x1 ... xn" (nan for a missing reading) from stdin, predicts each through the
 * model file's guard, and prints "%.17g status" per row ("- status" while waiting). */
#include <stdio.h>
#include <stdlib.h>

#include "thermerr_edge.h"

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: guarded MODEL.json < rows\n");
        return 2;
    }
    te_model *m = te_open(argv[1]);
    if (!m) {
        fprintf(stderr, "te_open: %s\n", te_last_error());
        return 1;
    }
    if (te_has_guard(m) != 1) return 3;
    int n = te_n_features(m);
    double *x = malloc(sizeof(double) * (size_t)n);
    double t, y;
    char status[8]; /* deliberately short: the status is truncated, never overrun */
    char full[256];
    for (;;) {
        if (scanf("%lf", &t) != 1) break;
        for (int j = 0; j < n; j++)
            if (scanf("%lf", &x[j]) != 1) goto done;
        int rc = te_predict_guarded(m, t, x, (size_t)n, &y, full, sizeof full);
        if (rc == TE_OK)
            printf("%.17g %s\n", y, full);
        else if (rc == TE_WAITING)
            printf("- %s\n", full);
        else {
            fprintf(stderr, "te_predict_guarded: %d %s\n", rc, te_last_error());
            return 1;
        }
    }
done:
    /* the short buffer on a fresh run: truncated to 7 bytes and NUL-terminated */
    te_reset(m);
    for (int j = 0; j < n; j++) x[j] = 0.0 / 0.0;
    if (te_predict_guarded(m, 0.0, x, (size_t)n, &y, status, sizeof status) != TE_WAITING) return 4;
    fprintf(stderr, "%s\n", status);
    free(x);
    te_close(m);
    return 0;
}
