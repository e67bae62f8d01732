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
 * A machine model (mtec.machine-error/1: geometric map + thermal models) has a state: once per
 * cycle, before the correction, pass the readings named by mtec_rt_state_input_name(rt, i)
 * (i < mtec_rt_state_input_count(rt); temperatures in degC, spindle speed in rpm) and the
 * seconds since the last update:
 *
 *   int s = mtec_rt_update_state(rt, readings, n, dt_s);   (MTEC_RT_ENVELOPE: thermal part faded)
 *
 * Thread rules: a handle belongs to one thread at a time; never call mtec_rt_update_state while
 * another thread calls mtec_rt_correction on the same handle. Load and free outside the
 * real-time loop (they allocate); update and correction do not allocate.
 *
 * Hand-written; keep in step with crates/mtec-rt/src/lib.rs (tests/c_header.rs compiles a C
 * program against it).
 */
#ifndef MTEC_RT_H
#define MTEC_RT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Return codes of mtec_rt_correction. */
#define MTEC_RT_OK 0
#define MTEC_RT_ERR_NULL (-1)          /* NULL handle or output pointer */
#define MTEC_RT_ERR_UNDEFINED 1        /* no model value there (outside a map that refuses) */
#define MTEC_RT_ERR_NOT_CONVERGED 2    /* correction did not converge */
#define MTEC_RT_ERR_TOO_LARGE 3        /* correction longer than 500 um */
#define MTEC_RT_ENVELOPE 4             /* state updated; a reading outside the training range:
                                          thermal part faded (mtec_rt_thermal_weight) */
#define MTEC_RT_ERR_STATE 5            /* state update refused (count, NaN, dt < 0); unchanged */

/* Opaque handle of a loaded model. */
typedef struct MtecRt MtecRt;

/* Loads a model file (mtec.map/1, mtec.kinematic-model/1, mtec.bpnn/1, mtec.machine-error/1).
   NULL on failure:
   see mtec_rt_last_error(). */
MtecRt *mtec_rt_load(const char *path);

/* Message of the last failed mtec_rt_load on this thread ("" if none). */
const char *mtec_rt_last_error(void);

/* Correction (um) for the target (x, y, z) mm, written to out_um[0..2]. */
int mtec_rt_correction(const MtecRt *handle, double x_mm, double y_mm, double z_mm, double *out_um);

/* Number of state readings mtec_rt_update_state takes (0: a static model). */
size_t mtec_rt_state_input_count(const MtecRt *handle);

/* Name of state reading i ("t3_c", "spindle_rpm", ...), NULL if i is out of range. Lives as long
   as the handle. */
const char *mtec_rt_state_input_name(const MtecRt *handle, size_t i);

/* Advances the state by dt_s seconds with n readings. MTEC_RT_OK, MTEC_RT_ENVELOPE,
   MTEC_RT_ERR_STATE or MTEC_RT_ERR_NULL. */
int mtec_rt_update_state(MtecRt *handle, const double *readings, size_t n, double dt_s);

/* Thermal weight after the last update: 1 inside the training envelope, towards 0 outside. */
double mtec_rt_thermal_weight(const MtecRt *handle);

/* Releases a handle (NULL is ignored). */
void mtec_rt_free(MtecRt *handle);

#ifdef __cplusplus
}
#endif

#endif /* MTEC_RT_H */
