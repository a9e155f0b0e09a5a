/* FMI 2.0 Co-Simulation wrapper of maglevkit's reduced current-based magnet model.

   Written for maglevkit (MIT licence).  The model itself, eq. 8 of the paper "Modeling of
   the Transrapid's Electromagnets and the Application to Large Mechatronic Vehicle
   Models" for every circuit, integrated by classical RK4, and the characteristic maps as
   per-cell polynomial tables, is CasADi-generated C (model.c/model.h): the same
   expressions as maglevkit.MagnetBank.  This file adds the FMI 2.0 interface:

   - state machine instantiated -> initialization mode -> step mode -> terminated
     (fmi2Reset back to instantiated; fmi2Error is final until fmi2Reset/fmi2FreeInstance);
   - value references in blocks of NC (config.h): inputs U, s, sdot; outputs I, F; local
     I_L; parameters R_el, R_ec, I0; then F_total and max_substep;
   - fmi2DoStep: ceil(h / max_substep) RK4 sub-steps (SUBSTEP_COUNT, config.h: the rule of
     maglevkit.reduced.core); the gap moves linearly from its value at the communication
     point with the gap rate (exact at the RK4 stage times);
   - a sub-step the kernel flags (gap path or current outside the maps, non-finite values:
     its reason codes, maglevkit.reduced.core.StepFlag): fmi2Error and a log message, the
     one MagnetBank.step gives (the templates of STEP_FLAG_MESSAGES in config.h), naming
     the circuit, the value and the range; the state is left as it was before the step.
     Nothing is clamped.
   - with MOTION_EDDY (config.h) every circuit carries a second state, the shielding eddy
     current I_e of the shielded-gap ladder (0 in eq. 8 circuits; started at 0, the
     steady state), advanced and restored with I_L; with N_EDDY 2 (three-state ladder
     members) two, I_e1 and I_e2 (stored as the kernel reads them: I_e1 of every circuit,
     then I_e2).
*/

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"
#include "config.h"

#define VR_U(j) ((j))
#define VR_S(j) (NC + (j))
#define VR_SDOT(j) (2 * NC + (j))
#define VR_I(j) (3 * NC + (j))
#define VR_F(j) (4 * NC + (j))
#define VR_IL(j) (5 * NC + (j))
#define VR_REL(j) (6 * NC + (j))
#define VR_REC(j) (7 * NC + (j))
#define VR_I0(j) (8 * NC + (j))
#define VR_FTOTAL (9 * NC)
#define VR_MAXSTEP (9 * NC + 1)
#define N_VR (9 * NC + 2)

typedef enum { ST_INSTANTIATED, ST_INIT, ST_STEP, ST_TERMINATED, ST_ERROR } ModelState;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    fmi2Boolean logging;
    ModelState state;
    double time;
    double r[N_VR];           /* inputs and parameters as set; outputs filled on demand */
    double x[NC];             /* I_L, the ODE state [A] */
    double s_now[NC];         /* the gap now [m]: as set, moved by sdot over each step */
    double par[NC * N_PAR];   /* kernel parameters (column per circuit) */
    double xs[NC], coil[NC], force[NC], lo[NC], hi[NC], bad[NC], lt[NC];
#if MOTION_EDDY
    double xe[NC * N_EDDY], xes[NC * N_EDDY];   /* I_e, the ladder's eddy states [A], and
                                                  their step result */
#endif
    double s_arg[NC], h_arg;
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
} Model;

/* ------------------------------------------------------------------ logging */
static void log_message(Model *m, fmi2Status status, const char *category, const char *fmt, ...) {
    char buf[1024];
    size_t k;
    va_list ap;
    if (m == NULL || m->cb.logger == NULL) return;
    if (status == fmi2OK && !m->logging) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    /* the message is passed pre-formatted: no printf directives, no variable references */
    for (k = 0; buf[k]; ++k)
        if (buf[k] == '%' || buf[k] == '#') buf[k] = '_';
    m->cb.logger(m->cb.componentEnvironment, m->name, status, category, buf);
}

static fmi2Status fail(Model *m, const char *fmt, ...) {
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    log_message(m, fmi2Error, "logStatusError", "%s", buf);
    m->state = ST_ERROR;
    return fmi2Error;
}

static const char *state_name(ModelState s);

static fmi2Status refuse(Model *m, const char *fn, const char *why) {
    /* a call not allowed in this state or not supported: fmi2Error, state unchanged */
    if (m != NULL)
        log_message(m, fmi2Error, "logStatusError", "%s: %s (the FMU is in %s)", fn, why,
                    state_name(m->state));
    return fmi2Error;
}

static const char *state_name(ModelState s) {
    switch (s) {
        case ST_INSTANTIATED: return "instantiated";
        case ST_INIT: return "initialization mode";
        case ST_STEP: return "step mode";
        case ST_TERMINATED: return "terminated";
        default: return "error";
    }
}

static int is_finite(double v) { return fabs(v) <= DBL_MAX; }

/* ------------------------------------------------------------------ model pieces */
static void set_defaults(Model *m) {
    int j;
    for (j = 0; j < NC; ++j) {
        m->r[VR_U(j)] = START_U[j];
        m->r[VR_S(j)] = START_S[j];
        m->r[VR_SDOT(j)] = 0.0;
        m->r[VR_REL(j)] = START_R_EL[j];
        m->r[VR_REC(j)] = START_R_EC[j];
        m->r[VR_I0(j)] = START_I0[j];
        m->s_now[j] = START_S[j];
        m->x[j] = START_I0[j];
    }
#if MOTION_EDDY
    for (j = 0; j < NC * N_EDDY; ++j) m->xe[j] = 0.0;
#endif
    m->r[VR_MAXSTEP] = START_MAX_SUBSTEP;
    memcpy(m->par, PAR0, sizeof m->par);
    m->time = 0.0;
}

static void update_parameters(Model *m) {
    int j;
    for (j = 0; j < NC; ++j) {
        double r_el = m->r[VR_REL(j)], r_ec = m->r[VR_REC(j)];
        m->par[N_PAR * j + PAR_R_EL] = r_el;
        m->par[N_PAR * j + PAR_A] = isinf(r_ec) ? 1.0 : 1.0 + r_el / r_ec;
    }
}

static int eval_step(Model *m, const double *s, double h) {
    int j;
    for (j = 0; j < NC; ++j) m->s_arg[j] = s[j];
    m->h_arg = h;
    m->arg[0] = m->x;
    m->arg[1] = m->s_arg;
    m->arg[2] = m->r + VR_U(0);
    m->arg[3] = m->r + VR_SDOT(0);
    m->arg[4] = &m->h_arg;
    m->arg[5] = m->par;
    m->res[0] = m->xs;
    m->res[1] = m->coil;
    m->res[2] = m->force;
    m->res[3] = m->lo;
    m->res[4] = m->hi;
    m->res[5] = m->bad;
#if MOTION_EDDY
    m->arg[6] = m->xe;
    m->res[6] = m->xes;
#endif
    return MK_STEP(m->arg, m->res, m->iw, m->w, 0);
}

static int eval_outputs(Model *m) {
    m->arg[0] = m->x;
    m->arg[1] = m->s_now;
    m->arg[2] = m->r + VR_U(0);
    m->arg[3] = m->par;
#if MOTION_EDDY
    m->arg[4] = m->xe;
#endif
    m->res[0] = m->coil;
    m->res[1] = m->force;
    m->res[2] = m->lt;
    return MK_OUT(m->arg, m->res, m->iw, m->w, 0);
}

/* the messages below are maglevkit.reduced.core.STEP_FLAG_MESSAGES (config.h): the same
   text as MagnetBank.step */
static void out_of_maps(Model *m, int j, const char *where, double s, double i) {
    fail(m, MSG_OUT_OF_MAPS MSG_ADVICE_FMU, CIRCUIT_LABELS[j], where, s, i, GAP_MIN[j],
         GAP_MAX[j], CUR_MIN[j], CUR_MAX[j]);
}

/* checks of the inputs that the outputs (and initialization) use, where no step runs to
   flag them; returns 0 if fine */
static int check_gap(Model *m, int j, double s, const char *where) {
    if (!is_finite(s)) {
        fail(m, MSG_INPUT_NOT_FINITE, "gaps", BANK_CIRCUITS[j], s, "m");
        return 1;
    }
    if (s < GAP_LO[j] || s > GAP_HI[j]) {
        out_of_maps(m, j, where, s, m->x[j]);
        return 1;
    }
    return 0;
}

static int check_current(Model *m, int j, double i, const char *where) {
    if (!is_finite(i)) {
        fail(m, MSG_RESULT_NOT_FINITE, BANK_CIRCUITS[j]);
        return 1;
    }
    if (i < CUR_LO[j] || i > CUR_HI[j]) {
        out_of_maps(m, j, where, m->s_now[j], i);
        return 1;
    }
    return 0;
}

/* the message of a sub-step the kernel flagged, from its reason codes
   (maglevkit.reduced.core.StepFlag) alone, as MagnetBank.step words it: reasons in the
   order of StepFlag.by_priority(), each for the first circuit that has it.  The step runs
   from t0 to t1 with the gaps s0 and the currents i0 at t0 */
static void report_step_flags(Model *m, const double *s0, const double *i0, double t0,
                              double t1) {
    static const int priority[] = STEP_FLAG_PRIORITY;
    char where[160];
    size_t p;
    int j;
    for (p = 0; p < sizeof priority / sizeof priority[0]; ++p) {
        int reason = priority[p];
        for (j = 0; j < NC; ++j) {
            double sdot = m->r[VR_SDOT(j)], se = s0[j] + sdot * (t1 - t0);
            if (!((int)m->bad[j] & reason)) continue;
            if (reason == STEP_FLAG_INPUT_NOT_FINITE) {
                if (!is_finite(m->r[VR_U(j)]))
                    fail(m, MSG_INPUT_NOT_FINITE, "voltages", BANK_CIRCUITS[j], m->r[VR_U(j)], "V");
                else if (!is_finite(s0[j]))
                    fail(m, MSG_INPUT_NOT_FINITE, "gaps", BANK_CIRCUITS[j], s0[j], "m");
                else
                    fail(m, MSG_INPUT_NOT_FINITE, "gap_rates", BANK_CIRCUITS[j], sdot, "m/s");
            } else if (reason == STEP_FLAG_GAP_OUT_OF_RANGE) {
                double lo = s0[j] < se ? s0[j] : se, hi = s0[j] < se ? se : s0[j];
                if (s0[j] <= 0.0 || se <= 0.0) {
                    fail(m, MSG_GAP_NOT_POSITIVE, BANK_CIRCUITS[j], s0[j], se);
                } else {
                    snprintf(where, sizeof where, MSG_STEP, t0, t1);
                    out_of_maps(m, j, where, lo < GAP_LO[j] ? lo : hi, i0[j]);
                }
            } else if (reason == STEP_FLAG_RESULT_NOT_FINITE) {
                fail(m, MSG_RESULT_NOT_FINITE, BANK_CIRCUITS[j]);
            } else if (!(i0[j] >= CUR_LO[j] && i0[j] <= CUR_HI[j])) {  /* at the start */
                snprintf(where, sizeof where, MSG_STEP, t0, t1);
                out_of_maps(m, j, where, s0[j], i0[j]);
            } else {                                                  /* in a sub-step */
                snprintf(where, sizeof where, MSG_SUBSTEP, t0, t1);
                out_of_maps(m, j, where, se, m->lo[j] < CUR_LO[j] ? m->lo[j] : m->hi[j]);
            }
            return;
        }
    }
    fail(m, "the step was flagged without a known reason code");
}

static int check_parameters(Model *m) {
    int j;
    double h = m->r[VR_MAXSTEP];
    if (!(is_finite(h) && h > 0.0))
        return fail(m, "max_substep = %g s must be a finite number > 0", h), 1;
    for (j = 0; j < NC; ++j) {
        double r_el = m->r[VR_REL(j)], r_ec = m->r[VR_REC(j)];
        if (!(is_finite(r_el) && r_el > 0.0))
            return fail(m, "circuit %s: R_el = %g ohm must be a finite number > 0", CIRCUIT_NAMES[j],
                        r_el), 1;
        if (!(r_ec > 0.0))   /* +inf: no eddy currents (a = 1); NaN fails here */
            return fail(m, "circuit %s: R_ec = %g ohm must be > 0 (inf: no eddy currents)",
                        CIRCUIT_NAMES[j], r_ec), 1;
    }
    return 0;
}

static int check_inputs(Model *m, const char *where) {
    int j;
    for (j = 0; j < NC; ++j) {
        if (!is_finite(m->r[VR_U(j)]))
            return fail(m, MSG_INPUT_NOT_FINITE, "voltages", BANK_CIRCUITS[j], m->r[VR_U(j)],
                        "V"), 1;
        if (!is_finite(m->r[VR_SDOT(j)]))
            return fail(m, MSG_INPUT_NOT_FINITE, "gap_rates", BANK_CIRCUITS[j], m->r[VR_SDOT(j)],
                        "m/s"), 1;
        if (check_gap(m, j, m->s_now[j], where)) return 1;
        if (check_current(m, j, m->x[j], where)) return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------ common functions */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Model *m = (Model *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    for (k = 0; k < nCategories; ++k) {
        if (categories == NULL || categories[k] == NULL ||
            (strcmp(categories[k], "logStatusError") != 0 && strcmp(categories[k], "logAll") != 0))
            return refuse(m, "fmi2SetDebugLogging", "unknown log category (use logStatusError or logAll)");
    }
    m->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Model *m;
    casadi_int sz_arg, sz_res, sz_iw, sz_w, a2, r2, i2, w2;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL)
        return NULL;
    if (instanceName == NULL) instanceName = "";
    if (fmuType != fmi2CoSimulation || fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              fmuType != fmi2CoSimulation
                                  ? "fmi2Instantiate: this FMU supports co-simulation only"
                                  : "fmi2Instantiate: the GUID does not match modelDescription.xml");
        return NULL;
    }
    m = (Model *)functions->allocateMemory(1, sizeof(Model));
    if (m == NULL) return NULL;
    m->cb = *functions;
    m->name = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
    if (m->name != NULL) strcpy(m->name, instanceName);
    MK_STEP_WORK(&sz_arg, &sz_res, &sz_iw, &sz_w);
    MK_OUT_WORK(&a2, &r2, &i2, &w2);
    if (a2 > sz_arg) sz_arg = a2;
    if (r2 > sz_res) sz_res = r2;
    if (i2 > sz_iw) sz_iw = i2;
    if (w2 > sz_w) sz_w = w2;
    m->arg = (const casadi_real **)functions->allocateMemory((size_t)sz_arg + 1, sizeof(casadi_real *));
    m->res = (casadi_real **)functions->allocateMemory((size_t)sz_res + 1, sizeof(casadi_real *));
    m->iw = (casadi_int *)functions->allocateMemory((size_t)sz_iw + 1, sizeof(casadi_int));
    m->w = (casadi_real *)functions->allocateMemory((size_t)sz_w + 1, sizeof(casadi_real));
    if (m->name == NULL || m->arg == NULL || m->res == NULL || m->iw == NULL || m->w == NULL) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Fatal,
                              "logStatusError", "fmi2Instantiate: out of memory");
        fmi2FreeInstance(m);
        return NULL;
    }
    m->logging = loggingOn;
    m->state = ST_INSTANTIATED;
    set_defaults(m);
    log_message(m, fmi2OK, "logAll", "instantiated %s (%d circuits)", MODEL_IDENTIFIER, NC);
    return m;
}

void fmi2FreeInstance(fmi2Component c) {
    Model *m = (Model *)c;
    fmi2CallbackFreeMemory release;
    if (m == NULL) return;
    release = m->cb.freeMemory;
    if (m->arg) release((void *)m->arg);
    if (m->res) release(m->res);
    if (m->iw) release(m->iw);
    if (m->w) release(m->w);
    if (m->name) release(m->name);
    release(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Model *m = (Model *)c;
    (void)toleranceDefined;
    (void)tolerance;   /* fixed-step RK4: the step is set by max_substep, not a tolerance */
    (void)stopTimeDefined;
    (void)stopTime;
    if (m == NULL) return fmi2Error;
    if (m->state != ST_INSTANTIATED)
        return refuse(m, "fmi2SetupExperiment", "only allowed after fmi2Instantiate");
    if (!is_finite(startTime)) return fail(m, "fmi2SetupExperiment: startTime = %g s is not finite", startTime);
    m->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (m->state != ST_INSTANTIATED)
        return refuse(m, "fmi2EnterInitializationMode", "only allowed after fmi2Instantiate");
    m->state = ST_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Model *m = (Model *)c;
    int j;
    if (m == NULL) return fmi2Error;
    if (m->state != ST_INIT)
        return refuse(m, "fmi2ExitInitializationMode", "only allowed in initialization mode");
    for (j = 0; j < NC; ++j) m->x[j] = m->r[VR_I0(j)];
#if MOTION_EDDY
    for (j = 0; j < NC * N_EDDY; ++j) m->xe[j] = 0.0;   /* the steady state of the ladder */
#endif
    if (check_parameters(m) || check_inputs(m, " at initialization")) return fmi2Error;
    update_parameters(m);
    m->state = ST_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (m->state != ST_STEP)
        return refuse(m, "fmi2Terminate", "only allowed in step mode");
    m->state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    set_defaults(m);
    m->state = ST_INSTANTIATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------ get / set */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Model *m = (Model *)c;
    size_t k;
    int computed = 0;
    if (m == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return refuse(m, "fmi2GetReal", "NULL argument");
    if (m->state == ST_INSTANTIATED && nvr > 0)
        return refuse(m, "fmi2GetReal", "not allowed before fmi2EnterInitializationMode");
    for (k = 0; k < nvr; ++k) {
        fmi2ValueReference v = vr[k];
        if (v >= N_VR) return refuse(m, "fmi2GetReal", "unknown value reference");
        if ((v >= VR_I(0) && v < VR_IL(0)) || v == VR_FTOTAL) {
            if (!computed) {
                int j;
                if (m->state == ST_INIT) {
                    update_parameters(m);
                    for (j = 0; j < NC; ++j) m->x[j] = m->r[VR_I0(j)];
                }
                /* outputs at the gap and current now: refused outside the maps */
                for (j = 0; j < NC; ++j) {
                    if (check_gap(m, j, m->s_now[j], " (fmi2GetReal of the outputs)")) return fmi2Error;
                    if (check_current(m, j, m->x[j], " (fmi2GetReal of the outputs)")) return fmi2Error;
                    if (!is_finite(m->r[VR_U(j)]))
                        return fail(m, "circuit %s: voltage U = %g V is not finite", CIRCUIT_NAMES[j],
                                    m->r[VR_U(j)]);
                }
                if (eval_outputs(m)) return fail(m, "fmi2GetReal: evaluating the outputs failed");
                computed = 1;
            }
            if (v == VR_FTOTAL) {
                int j;
                double sum = 0.0;
                for (j = 0; j < NC; ++j) sum += m->force[j];
                value[k] = sum;
            } else if (v < VR_F(0)) {
                value[k] = m->coil[v - VR_I(0)];
            } else {
                value[k] = m->force[v - VR_F(0)];
            }
        } else if (v >= VR_IL(0) && v < VR_REL(0)) {
            int j = (int)(v - VR_IL(0));
            value[k] = m->state == ST_INIT ? m->r[VR_I0(j)] : m->x[j];
        } else {
            value[k] = m->r[v];
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Model *m = (Model *)c;
    size_t k;
    if (m == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return refuse(m, "fmi2SetReal", "NULL argument");
    if (m->state == ST_TERMINATED || m->state == ST_ERROR)
        return refuse(m, "fmi2SetReal", "not allowed after fmi2Terminate or an error");
    for (k = 0; k < nvr; ++k) {
        fmi2ValueReference v = vr[k];
        double val = value[k];
        if (v >= N_VR) return refuse(m, "fmi2SetReal", "unknown value reference");
        if ((v >= VR_I(0) && v < VR_REL(0)) || v == VR_FTOTAL)
            return refuse(m, "fmi2SetReal", "outputs and the state I_L cannot be set");
        if (m->state == ST_STEP && ((v >= VR_I0(0) && v < VR_FTOTAL) || v == VR_MAXSTEP))
            return refuse(m, "fmi2SetReal", "I0 and max_substep are fixed parameters: set them "
                                            "before fmi2ExitInitializationMode");
        if (!(fabs(val) <= DBL_MAX) && !(v >= VR_REC(0) && v < VR_I0(0) && val > 0.0)) {
            /* non-finite values are refused at once (R_ec = +inf is allowed) */
            return fail(m, "fmi2SetReal: value reference %u gets the non-finite value %g",
                        (unsigned)v, val);
        }
        m->r[v] = val;
        if (v >= VR_S(0) && v < VR_SDOT(0)) m->s_now[v - VR_S(0)] = val;
    }
    if (m->state == ST_STEP) {
        for (k = 0; k < nvr; ++k)
            if (vr[k] >= VR_REL(0) && vr[k] < VR_I0(0)) {
                if (check_parameters(m)) return fmi2Error;
                update_parameters(m);
                break;
            }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2GetInteger", "the FMU has no Integer variables");
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2GetBoolean", "the FMU has no Boolean variables");
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2GetString", "the FMU has no String variables");
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2SetInteger", "the FMU has no Integer variables");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2SetBoolean", "the FMU has no Boolean variables");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : refuse((Model *)c, "fmi2SetString", "the FMU has no String variables");
}

/* ------------------------------------------------------------------ not supported */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return refuse((Model *)c, "fmi2GetFMUstate", "not supported (canGetAndSetFMUstate=false)");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    (void)s;
    return refuse((Model *)c, "fmi2SetFMUstate", "not supported (canGetAndSetFMUstate=false)");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return refuse((Model *)c, "fmi2FreeFMUstate", "not supported (canGetAndSetFMUstate=false)");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)s; (void)size;
    return refuse((Model *)c, "fmi2SerializedFMUstateSize", "not supported");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size) {
    (void)s; (void)b; (void)size;
    return refuse((Model *)c, "fmi2SerializeFMUstate", "not supported");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s) {
    (void)s; (void)b; (void)size;
    return refuse((Model *)c, "fmi2DeSerializeFMUstate", "not supported");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vu[], size_t nu,
                                        const fmi2ValueReference vk[], size_t nk,
                                        const fmi2Real dvk[], fmi2Real dvu[]) {
    (void)vu; (void)nu; (void)vk; (void)nk; (void)dvk; (void)dvu;
    return refuse((Model *)c, "fmi2GetDirectionalDerivative",
                  "not supported (providesDirectionalDerivative=false)");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return refuse((Model *)c, "fmi2SetRealInputDerivatives",
                  "not supported (canInterpolateInputs=false; the gap rate is an input of its own)");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return refuse((Model *)c, "fmi2GetRealOutputDerivatives", "not supported (maxOutputDerivativeOrder=0)");
}
fmi2Status fmi2CancelStep(fmi2Component c) {
    return refuse((Model *)c, "fmi2CancelStep", "not supported (fmi2DoStep never runs asynchronously)");
}

/* ------------------------------------------------------------------ stepping */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Model *m = (Model *)c;
    double h = communicationStepSize, t0, hs, x0[NC], s0[NC], sk[NC];
#if MOTION_EDDY
    double e0[NC * N_EDDY];
#endif
    long n, k;
    int j;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (m == NULL) return fmi2Error;
    if (m->state != ST_STEP) return refuse(m, "fmi2DoStep", "only allowed in step mode");
    t0 = m->time;
    if (!(is_finite(h) && h > 0.0))
        return fail(m, "fmi2DoStep at t = %.9g s: communicationStepSize = %g s must be > 0", t0, h);
    if (!(fabs(currentCommunicationPoint - t0) <= 1e-9 * (fabs(t0) + h)))
        return fail(m, "fmi2DoStep: currentCommunicationPoint = %.12g s, but the FMU is at t = %.12g s",
                    currentCommunicationPoint, t0);
    /* no checks of our own: the kernel flags the gap path, the currents and non-finite
       values of every sub-step, and its reason codes give the message */
    for (j = 0; j < NC; ++j) {
        s0[j] = m->s_now[j];
        x0[j] = m->x[j];
    }
#if MOTION_EDDY
    memcpy(e0, m->xe, sizeof e0);
#endif
    /* RK4 sub-steps of at most max_substep (the rule of maglevkit's models, config.h) */
    n = SUBSTEP_COUNT(h, m->r[VR_MAXSTEP]);
    hs = h / (double)n;
    for (k = 0; k < n; ++k) {
        for (j = 0; j < NC; ++j) sk[j] = s0[j] + m->r[VR_SDOT(j)] * ((double)k * hs);
        if (eval_step(m, sk, hs)) {
            memcpy(m->x, x0, sizeof x0);
#if MOTION_EDDY
            memcpy(m->xe, e0, sizeof e0);
#endif
            return fail(m, "fmi2DoStep at t = %.9g s: the model evaluation failed", t0);
        }
        for (j = 0; j < NC; ++j) {
            /* the kernel's reason code (maglevkit.reduced.core.StepFlag), not a check of our own */
            if (m->bad[j] != 0.0) {
                report_step_flags(m, s0, x0, t0, t0 + h);
                memcpy(m->x, x0, sizeof x0);   /* the state before the step */
#if MOTION_EDDY
                memcpy(m->xe, e0, sizeof e0);
#endif
                return fmi2Error;
            }
        }
        memcpy(m->x, m->xs, sizeof m->xs);
#if MOTION_EDDY
        memcpy(m->xe, m->xes, sizeof m->xes);
#endif
    }
    for (j = 0; j < NC; ++j) m->s_now[j] = s0[j] + m->r[VR_SDOT(j)] * h;
    m->time = t0 + h;
    return fmi2OK;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    return refuse((Model *)c, "fmi2GetStatus", "no asynchronous step: nothing pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Model *m = (Model *)c;
    if (m == NULL || value == NULL) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return refuse(m, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime");
    *value = m->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    return refuse((Model *)c, "fmi2GetIntegerStatus", "no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Model *m = (Model *)c;
    if (m == NULL || value == NULL) return fmi2Error;
    if (s != fmi2Terminated) return refuse(m, "fmi2GetBooleanStatus", "only fmi2Terminated");
    *value = fmi2False;   /* the FMU never asks to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    return refuse((Model *)c, "fmi2GetStringStatus", "no string status");
}
