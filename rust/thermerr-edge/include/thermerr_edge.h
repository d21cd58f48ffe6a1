/* thermerr_edge.h: C ABI of the thermerr-edge predictor (link libthermerr_edge.a or .so).
 *
 *   te_model *m = te_open("model.json");           // NULL on failure: te_last_error()
 *   double x[4] = {...}, y;                         // readings in the model's feature order
 *   if (te_predict(m, x, 4, &y) != TE_OK) puts(te_last_error());
 *   te_reset(m);                                    // a new run (models on rises or 1-AGO)
 *   te_close(m);
 *
 * Through the file's sensor-fault guard (thermerr fit writes one), raw readings with NaN for a
 * missing one, as thermerr-edge does:
 *
 *   char st[128];
 *   int rc = te_predict_guarded(m, t_seconds, x, 4, &y, st, sizeof st);
 *   // TE_OK: y predicted, st "ok" or e.g. "held:T_3"; TE_WAITING: nothing yet ("waiting:T_3")
 *
 * te_predict and te_predict_guarded keep separate run state: use one of them for a run.
 * Neither allocates on success. No function lets a Rust panic escape.
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
#define TE_ERR_NOGUARD (-5)  /* te_predict_guarded: the model file has no guard */
#define TE_WAITING 1         /* te_predict_guarded: no prediction yet (a sensor never read well) */

te_model *te_open(const char *path);
int te_n_features(const te_model *m);
int te_predict(te_model *m, const double *x, size_t n, double *out);
int te_has_guard(const te_model *m);
/* t: seconds (NaN: row count times the guard's step); status: NULL or status_len bytes */
int te_predict_guarded(te_model *m, double t, const double *x, size_t n, double *out,
                       char *status, size_t status_len);
/* the readings the rises are taken from, instead of each run's first sample (a gateway started
 * mid-run: e.g. the training run's first row); kept across te_reset */
int te_set_reference(te_model *m, const double *x, size_t n);
void te_reset(te_model *m);
void te_close(te_model *m);
const char *te_last_error(void);

#ifdef __cplusplus
}
#endif

#endif /* THERMERR_EDGE_H */
