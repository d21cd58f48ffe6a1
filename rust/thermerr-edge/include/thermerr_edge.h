/* thermerr_edge.h: C ABI of the thermerr-edge predictor (link libthermerr_edge.a or .so).
 *
 *   te_model *m = te_open("model.json");           // NULL on failure: te_last_error()
 *   double x[4] = {...}, y;                         // readings in the model's feature order
 *   if (te_predict(m, x, 4, &y) != TE_OK) puts(te_last_error());
 *   te_reset(m);                                    // a new run (models on rises or 1-AGO)
 *   te_close(m);
 *
 * te_predict allocates nothing on success. No function lets a Rust panic escape.
 */
#ifndef THERMERR_EDGE_H
#define THERMERR_EDGE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct TeModel te_model;

#define TE_OK 0
#define TE_ERR_NULL (-1)     /* a NULL argument */
#define TE_ERR_FEATURES (-2) /* the wrong number of features */
#define TE_ERR_INPUT (-3)    /* a non-finite reading */
#define TE_ERR_PANIC (-4)    /* an internal error */

te_model *te_open(const char *path);
int te_n_features(const te_model *m);
int te_predict(te_model *m, const double *x, size_t n, double *out);
void te_reset(te_model *m);
void te_close(te_model *m);
const char *te_last_error(void);

#ifdef __cplusplus
}
#endif

#endif /* THERMERR_EDGE_H */
