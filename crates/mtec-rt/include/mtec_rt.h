/* mtec_rt.h: C interface of mtec's real-time compensation (crate mtec-rt).
 *
 * Load a model file once (outside the real-time loop), then call mtec_rt_correction once per
 * servo/interpolation cycle: it returns the correction in micrometres to ADD to the X, Y, Z axis
 * commands so that the tool reaches the target (x, y, z) in millimetres. It does not allocate,
 * lock or block. On failure the correction is set to zero and the return code says why.
 *
 *   MtecRt *rt = mtec_rt_load("map.json");
 *   if (!rt) { fprintf(stderr, "%s\n", mtec_rt_last_error()); return 1; }
 *   double c_um[3];
 *   if (mtec_rt_correction(rt, x, y, z, c_um) == MTEC_RT_OK) { x += c_um[0] * 1e-3; ... }
 *   mtec_rt_free(rt);
 *
 * Hand-written; keep in step with crates/mtec-rt/src/lib.rs (tests/c_header.rs compiles a C
 * program against it).
 */
#ifndef MTEC_RT_H
#define MTEC_RT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Return codes of mtec_rt_correction. */
#define MTEC_RT_OK 0
#define MTEC_RT_ERR_NULL (-1)          /* NULL handle or output pointer */
#define MTEC_RT_ERR_UNDEFINED 1        /* no model value there (outside a map that refuses) */
#define MTEC_RT_ERR_NOT_CONVERGED 2    /* correction did not converge */
#define MTEC_RT_ERR_TOO_LARGE 3        /* correction longer than 500 um */

/* Opaque handle of a loaded model. */
typedef struct MtecRt MtecRt;

/* Loads a model file (mtec.map/1, mtec.kinematic-model/1, mtec.bpnn/1). NULL on failure:
   see mtec_rt_last_error(). */
MtecRt *mtec_rt_load(const char *path);

/* Message of the last failed mtec_rt_load on this thread ("" if none). */
const char *mtec_rt_last_error(void);

/* Correction (um) for the target (x, y, z) mm, written to out_um[0..2]. */
int mtec_rt_correction(const MtecRt *handle, double x_mm, double y_mm, double z_mm, double *out_um);

/* Releases a handle (NULL is ignored). */
void mtec_rt_free(MtecRt *handle);

#ifdef __cplusplus
}
#endif

#endif /* MTEC_RT_H */
