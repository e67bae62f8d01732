// mtec_eoffset: mtec's compensation in LinuxCNC through the external axis offsets.
// Build and use: docs/linuxcnc.md. Realtime component for uspace LinuxCNC (the Debian package
// linuxcnc-uspace: POSIX non-realtime or PREEMPT_RT); it links libmtec_rt (crates/mtec-rt).
component mtec_eoffset """Compensates a machine's geometric and thermal error, predicted by an mtec model, through LinuxCNC's external axis offsets (axis.L.eoffset-*).""";

description """
Each servo period the component reads the commanded X, Y, Z position (\\fBaxis.L.pos-cmd\\fR, which
LinuxCNC reports without the external offsets), advances the model's thermal state with the
readings on \\fBtemp-NN\\fR, asks libmtec_rt for the correction that makes the tool reach that
position, and steers LinuxCNC's requested external offset (\\fBaxis.L.eoffset-request\\fR) to
it through \\fBaxis.L.eoffset-counts\\fR. The counts only change while \\fBmachine-on\\fR and
\\fBall-homed\\fR are true (LinuxCNC discards offset counts otherwise). On any error the
correction is zero, \\fBfault\\fR is set and \\fBstatus\\fR says why.

Load with \\fBloadrt mtec_eoffset model=/path/model.json personality=N\\fR, N the number of state
readings the model takes (0 for a static map); with a wrong N loading stops and lists the
model's readings in pin order. One instance only. Documentation: docs/linuxcnc.md in mtec.
""";

pin in float x_pos "Commanded X, machine units: net to axis.x.pos-cmd";
pin in float y_pos "Commanded Y: net to axis.y.pos-cmd";
pin in float z_pos "Commanded Z: net to axis.z.pos-cmd";
pin in float x_request "Requested X offset: net to axis.x.eoffset-request";
pin in float y_request "Requested Y offset: net to axis.y.eoffset-request";
pin in float z_request "Requested Z offset: net to axis.z.eoffset-request";
pin out s32 x_counts "Net to axis.x.eoffset-counts";
pin out s32 y_counts "Net to axis.y.eoffset-counts";
pin out s32 z_counts "Net to axis.z.eoffset-counts";
pin out float scale "Machine units per count (= resolution): net to axis.L.eoffset-scale";
pin in bit machine_on "Net to motion.motion-enabled";
pin in bit all_homed "Net to motion.is-all-homed";
pin in float temp_##[64 : personality] "State readings (degC, rpm) in the model's order (listed at load with the debug level at INFO, or when personality does not match)";
pin in bit temps_valid = 0 "True once the readings are real values: the thermal state starts at the first valid reading";
pin out float x_um "Correction requested for X, um";
pin out float y_um "Correction requested for Y, um";
pin out float z_um "Correction requested for Z, um";
pin out bit active "Offset counts are being sent (machine-on and all-homed)";
pin out s32 status "Last mtec_rt_correction code: 0 ok, 1 outside the model, 2 not converged, 3 over 500 um";
pin out s32 state_status "Last mtec_rt_update_state code: 0 ok, 4 outside the training envelope, 5 refused";
pin out bit fault "A correction or state update failed: the correction is zero (or the state is held)";
pin out bit envelope "A reading is outside the model's training range: the thermal part is faded";
pin out float thermal_weight "Weight of the thermal part: 1 inside the training envelope, down to 0 outside";
param rw float mm_per_unit = 1.0 "Millimetres per machine unit: 1 for a mm machine, 25.4 for an inch machine";
param rw float resolution = 1e-6 "Offset resolution, machine units per count";

function _;
option extra_setup yes;
option extra_cleanup yes;
license "GPL";
author "mtec";
include "../include/mtec_rt.h";
;;

static char *model = "";
RTAPI_MP_STRING(model, "mtec model file (mtec.map/1, mtec.machine-error/1, ...)");

static MtecRt *rt = NULL;
/* Seconds since the last state update (the readings were not valid in between). */
static double since_update = 0.0;

EXTRA_SETUP() {
    size_t n, i;
    if (extra_arg != 0) {
        rtapi_print_msg(RTAPI_MSG_ERR, "mtec_eoffset: one instance only (count=1)\n");
        return -EINVAL;
    }
    if (model == NULL || model[0] == '\0') {
        rtapi_print_msg(RTAPI_MSG_ERR, "mtec_eoffset: no model: loadrt mtec_eoffset model=FILE\n");
        return -EINVAL;
    }
    rt = mtec_rt_load(model);
    if (rt == NULL) {
        rtapi_print_msg(RTAPI_MSG_ERR, "mtec_eoffset: %s\n", mtec_rt_last_error());
        return -EINVAL;
    }
    n = mtec_rt_state_input_count(rt);
    for (i = 0; i < n; i++) {
        rtapi_print_msg(RTAPI_MSG_INFO, "mtec_eoffset: temp-%02d = %s\n", (int)i,
                        mtec_rt_state_input_name(rt, i));
    }
    if (n != (size_t)personality) {
        rtapi_print_msg(RTAPI_MSG_ERR,
                        "mtec_eoffset: %s takes %d state readings, personality is %d: "
                        "loadrt mtec_eoffset model=%s personality=%d\n",
                        model, (int)n, (int)personality, model, (int)n);
        for (i = 0; i < n; i++) {
            rtapi_print_msg(RTAPI_MSG_ERR, "mtec_eoffset:   temp-%02d = %s\n", (int)i,
                            mtec_rt_state_input_name(rt, i));
        }
        mtec_rt_free(rt);
        rt = NULL;
        return -EINVAL;
    }
    return 0;
}

EXTRA_CLEANUP() {
    mtec_rt_free(rt);
    rt = NULL;
}

/* Counts that move the requested offset from `request` to `target` (machine units), or 0 when
   the difference is not a finite number or beyond 1e9 counts. */
static rtapi_s32 counts_to(double target, double request, double res) {
    double d = (target - request) / res;
    if (!(d > -1e9 && d < 1e9)) return 0;
    return (rtapi_s32)(d >= 0.0 ? d + 0.5 : d - 0.5);
}

/* Adds without signed overflow: LinuxCNC only uses the difference between periods. */
static rtapi_s32 wrap_add(rtapi_s32 a, rtapi_s32 b) {
    return (rtapi_s32)((rtapi_u32)a + (rtapi_u32)b);
}

FUNCTION(_) {
    double c_um[3] = {0.0, 0.0, 0.0};
    double readings[64];
    double mm = mm_per_unit, res = resolution;
    int n = personality, i, rc, bad_state = 0;

    if (rt == NULL) return;
    if (!(mm > 0.0)) mm = 1.0;
    if (!(res > 0.0)) res = 1e-6;

    /* the thermal state: every period once the readings are valid */
    since_update += fperiod;
    if (n > 0 && temps_valid) {
        for (i = 0; i < n; i++) readings[i] = temp(i);
        rc = mtec_rt_update_state(rt, readings, (size_t)n, since_update);
        state_status = rc;
        if (rc == MTEC_RT_OK || rc == MTEC_RT_ENVELOPE) {
            since_update = 0.0;
        } else {
            bad_state = 1;
        }
        envelope = (rc == MTEC_RT_ENVELOPE);
        thermal_weight = mtec_rt_thermal_weight(rt);
    }

    /* the correction at the commanded position (mm in, um out) */
    rc = mtec_rt_correction(rt, x_pos * mm, y_pos * mm, z_pos * mm, c_um);
    status = rc;
    if (rc != MTEC_RT_OK) {
        c_um[0] = c_um[1] = c_um[2] = 0.0;
    }
    fault = (rc != MTEC_RT_OK) || bad_state;
    x_um = c_um[0];
    y_um = c_um[1];
    z_um = c_um[2];

    scale = res;
    active = machine_on && all_homed;
    if (!active) return;
    x_counts = wrap_add(x_counts, counts_to(c_um[0] * 1e-3 / mm, x_request, res));
    y_counts = wrap_add(y_counts, counts_to(c_um[1] * 1e-3 / mm, y_request, res));
    z_counts = wrap_add(z_counts, counts_to(c_um[2] * 1e-3 / mm, z_request, res));
}
