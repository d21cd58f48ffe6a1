/* Reads samples (whitespace-separated readings, one sample per line) from stdin, predicts each
 * with the model given on the command line, and prints the predictions with %.17g. */
#include <stdio.h>
#include <stdlib.h>

#include "thermerr_edge.h"

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: demo MODEL.json < samples\n");
        return 2;
    }
    te_model *m = te_open(argv[1]);
    if (!m) {
        fprintf(stderr, "te_open: %s\n", te_last_error());
        return 1;
    }
    int n = te_n_features(m);
    double *x = malloc(sizeof(double) * (size_t)n);
    double y;
    /* a wrong feature count is an error code, not a crash */
    if (te_predict(m, x, (size_t)n + 1, &y) != TE_ERR_FEATURES) return 3;
    for (;;) {
        for (int j = 0; j < n; j++)
            if (scanf("%lf", &x[j]) != 1) goto done;
        int rc = te_predict(m, x, (size_t)n, &y);
        if (rc != TE_OK) {
            fprintf(stderr, "te_predict: %d %s\n", rc, te_last_error());
            return 1;
        }
        printf("%.17g\n", y);
    }
done:
    free(x);
    te_close(m);
    return 0;
}
