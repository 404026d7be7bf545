/* mbcomp FMI 2.0 wrapper (Model Exchange and Co-Simulation) around a generated Lagrange program.
 *
 * Written by mbcomp from the FMI 2.0.x standard's function list (the types below are the
 * standard's ABI, declared here so the FMU carries no header of anyone else). The
 * including file defines, before this one:
 *   MBCOMP_ID, NQ, NU, NP, NH, NW, GUID, and the arrays P0[NP], Y0[NQ+NU], NOMINAL[NQ+NU];
 *   int mbcomp_fun(q, u, t, d, h, p, w, out) (the Lagrange index-1 right-hand side with
 *   Baumgarte gains d[0], d[1]) and int mbcomp_params(pv, h) (the hoisted parameter values).
 * Value references: 0..NP-1 parameters, NP..NP+NX-1 states [q, u], NP+NX..NP+2NX-1 their
 * derivatives. Co-Simulation steps the same right-hand side with the runtime's DOP853
 * (mbrt.h: error control at the experiment's tolerance, 1e-8 if none is given). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mbrt.h"

#define NX (NQ + NU)
#define VR_X NP
#define VR_DX (NP + NX)
#define NVR (NP + 2 * NX)

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;

#if defined(__GNUC__)
#define FMI2_EXPORT __attribute__((visibility("default")))
#else
#define FMI2_EXPORT
#endif

enum { M_INSTANTIATED, M_INIT, M_EVENT, M_CONT, M_TERMINATED, M_ERROR };

typedef struct {
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int logging, mode, dirty, cs;
    double t, alpha, beta, rtol;
    double p[NP + 1], h[NH + 1], y[NX + 1], dy[NX + 1], w[NW + 1], d[2], atol[NX + 1], y_end[NX + 1];
    double *work; /* Co-Simulation: the integrator's scratch (mbrt_dop853_work_size) */
} Inst;

static void say(Inst *c, fmi2Status s, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    if (!c || !c->logger || (s == fmi2OK && !c->logging)) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->logger(c->env, c->name, s, s == fmi2OK ? "logAll" : "logStatusError", "%s", msg);
}

/* the hoisted values of the current parameters; a parameter guard failing is an error: the
   program was generated for a decision these values change */
static fmi2Status refresh(Inst *c)
{
    int rc;
    if (!c->dirty) return fmi2OK;
    rc = mbcomp_params(c->p, c->h);
    if (rc) {
        say(c, fmi2Error, "the parameter values %s -> export the model again with these values",
            rc == 1 ? "change a decision taken when the program was generated (a parameter guard)"
                    : "give a non-finite value");
        c->mode = M_ERROR;
        return fmi2Error;
    }
    c->dirty = 0;
    return fmi2OK;
}

static fmi2Status derivatives(Inst *c)
{
    int i;
    if (refresh(c) != fmi2OK) return fmi2Error;
    c->d[0] = c->alpha;
    c->d[1] = c->beta;
    if (mbcomp_fun(c->y, c->y + NQ, c->t, c->d, c->h, c->p, c->w, c->dy)) {
        say(c, fmi2Error, "the right-hand side failed a guard at t=%g (a singular position, or a law's other "
            "branch): mbcomp's numeric path is not in the FMU", c->t);
        return fmi2Error;
    }
    for (i = 0; i < NX; i++) {
        if (!isfinite(c->dy[i])) {
            say(c, fmi2Error, "the derivative of state %d is not finite at t=%g", i, c->t);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

#define NEED(c) do { if (!(c)) return fmi2Error; if (((Inst *)(c))->mode == M_ERROR) return fmi2Error; } while (0)

FMI2_EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
FMI2_EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[])
{
    (void)n; (void)cats;
    if (!c) return fmi2Error;
    ((Inst *)c)->logging = on;
    return fmi2OK;
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                          const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging)
{
    Inst *c;
    (void)location; (void)visible;
    if (!cb || !cb->logger) return NULL;
    if (!name || !guid || strcmp(guid, GUID) != 0) {
        cb->logger(cb->componentEnvironment, name ? name : "?", fmi2Error, "logStatusError",
                   "wrong guid %s: this FMU's is %s (the model description and the binary must match)",
                   guid ? guid : "(null)", GUID);
        return NULL;
    }
    c = (Inst *)calloc(1, sizeof(Inst));
    if (!c) return NULL;
    c->name = (char *)malloc(strlen(name) + 1);
    if (!c->name) { free(c); return NULL; }
    c->cs = type == fmi2CoSimulation;
    if (c->cs) {
        c->work = (double *)calloc(mbrt_dop853_work_size(NX) + 1, sizeof(double));
        if (!c->work) { free(c->name); free(c); return NULL; }
    }
    c->rtol = 1e-8;
    strcpy(c->name, name);
    c->logger = cb->logger;
    c->env = cb->componentEnvironment;
    c->logging = logging;
    memcpy(c->p, P0, sizeof(double) * NP);
    memcpy(c->y, Y0, sizeof(double) * NX);
    c->alpha = ALPHA;
    c->beta = BETA;
    c->dirty = 1;
    c->mode = M_INSTANTIATED;
    return c;
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c)
{
    if (!c) return;
    free(((Inst *)c)->name);
    free(((Inst *)c)->work);
    free(c);
}

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real t0,
                                           fmi2Boolean stopDef, fmi2Real tStop)
{
    (void)stopDef; (void)tStop;
    NEED(c);
    ((Inst *)c)->t = t0;
    if (tolDef) {
        if (!(tol >= 1e-14 && tol < 1.0)) {
            say((Inst *)c, fmi2Error, "fmi2SetupExperiment: tolerance %g is out of range (1e-14 .. 1)", tol);
            return fmi2Error;
        }
        ((Inst *)c)->rtol = tol;
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    NEED(c);
    ((Inst *)c)->mode = M_INIT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    NEED(c);
    if (refresh((Inst *)c) != fmi2OK) return fmi2Error;
    ((Inst *)c)->mode = M_EVENT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c)
{
    if (!c) return fmi2Error;
    ((Inst *)c)->mode = M_TERMINATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    Inst *s = (Inst *)c;
    if (!c) return fmi2Error;
    memcpy(s->p, P0, sizeof(double) * NP);
    memcpy(s->y, Y0, sizeof(double) * NX);
    s->t = 0.0;
    s->dirty = 1;
    s->mode = M_INSTANTIATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    Inst *s = (Inst *)c;
    size_t i;
    int need_dx = 0;
    NEED(c);
    for (i = 0; i < n; i++) if (vr[i] >= VR_DX && vr[i] < NVR) need_dx = 1;
    if (need_dx && derivatives(s) != fmi2OK) return fmi2Error;
    for (i = 0; i < n; i++) {
        if (vr[i] < VR_X) value[i] = s->p[vr[i]];
        else if (vr[i] < VR_DX) value[i] = s->y[vr[i] - VR_X];
        else if (vr[i] < NVR) value[i] = s->dy[vr[i] - VR_DX];
        else { say(s, fmi2Error, "fmi2GetReal: no variable with value reference %u", vr[i]); return fmi2Error; }
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    Inst *s = (Inst *)c;
    size_t i;
    NEED(c);
    for (i = 0; i < n; i++) {
        if (vr[i] < VR_X) {
            if (s->mode != M_INSTANTIATED && s->mode != M_INIT) {
                say(s, fmi2Error, "fmi2SetReal: parameter %u is fixed after initialization", vr[i]);
                return fmi2Error;
            }
            s->p[vr[i]] = value[i];
            s->dirty = 1;
        } else if (vr[i] < VR_DX) {
            s->y[vr[i] - VR_X] = value[i];
        } else {
            say(s, fmi2Error, "fmi2SetReal: value reference %u cannot be set", vr[i]);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

static fmi2Status unsupported(fmi2Component c, const char *what)
{
    say((Inst *)c, fmi2Error, "%s is not supported by this FMU", what);
    return fmi2Error;
}

FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2GetInteger (no Integer variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2GetBoolean (no Boolean variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2GetString (no String variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2SetInteger (no Integer variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2SetBoolean (no Boolean variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
{ (void)vr; (void)v; return n ? unsupported(c, "fmi2SetString (no String variables)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{ (void)s; return unsupported(c, "fmi2GetFMUstate"); }
FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{ (void)s; return unsupported(c, "fmi2SetFMUstate"); }
FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{ (void)s; return unsupported(c, "fmi2FreeFMUstate"); }
FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{ (void)s; (void)n; return unsupported(c, "fmi2SerializedFMUstateSize"); }
FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ (void)s; (void)b; (void)n; return unsupported(c, "fmi2SerializeFMUstate"); }
FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{ (void)s; (void)b; (void)n; return unsupported(c, "fmi2DeSerializeFMUstate"); }
FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                                    const fmi2ValueReference z[], size_t nz, const fmi2Real du[],
                                                    fmi2Real dz[])
{ (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz; return unsupported(c, "fmi2GetDirectionalDerivative"); }

/* --- Model Exchange ---------------------------------------------------------------------- */
FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    NEED(c);
    ((Inst *)c)->mode = M_EVENT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e)
{
    NEED(c);
    if (!e) return fmi2Error;
    memset(e, 0, sizeof *e);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    NEED(c);
    ((Inst *)c)->mode = M_CONT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePrior,
                                                   fmi2Boolean *enterEventMode, fmi2Boolean *terminate)
{
    (void)noSetFMUStatePrior;
    NEED(c);
    if (!enterEventMode || !terminate) return fmi2Error;
    *enterEventMode = 0;
    *terminate = 0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t)
{
    NEED(c);
    ((Inst *)c)->t = t;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    NEED(c);
    if (nx != NX || !x) { say((Inst *)c, fmi2Error, "fmi2SetContinuousStates: %zu states given, %d expected", nx, NX); return fmi2Error; }
    memcpy(((Inst *)c)->y, x, sizeof(double) * NX);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    Inst *s = (Inst *)c;
    NEED(c);
    if (nx != NX || !dx) { say(s, fmi2Error, "fmi2GetDerivatives: %zu asked, %d states", nx, NX); return fmi2Error; }
    if (derivatives(s) != fmi2OK) return fmi2Error;
    memcpy(dx, s->dy, sizeof(double) * NX);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz)
{
    (void)z;
    NEED(c);
    return nz == 0 ? fmi2OK : unsupported(c, "event indicators (this FMU has none)");
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    NEED(c);
    if (nx != NX || !x) { say((Inst *)c, fmi2Error, "fmi2GetContinuousStates: %zu asked, %d states", nx, NX); return fmi2Error; }
    memcpy(x, ((Inst *)c)->y, sizeof(double) * NX);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    NEED(c);
    if (nx != NX || !x) return fmi2Error;
    memcpy(x, NOMINAL, sizeof(double) * NX);
    return fmi2OK;
}

/* --- Co-Simulation --------------------------------------------------------------------- */
static int cs_rhs(void *ctx, double t, const double *y, double *dydt)
{
    Inst *c = (Inst *)ctx;
    return mbcomp_fun(y, y + NQ, t, c->d, c->h, c->p, c->w, dydt);
}

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    Inst *s = (Inst *)c;
    mbrt_stats st;
    double t_end;
    int i, rc, written = 0;
    (void)noSetPrior;
    NEED(c);
    if (!s->cs) return unsupported(c, "fmi2DoStep in a Model Exchange instance");
    if (!(h >= 0.0) || fabs(t - s->t) > 1e-9 * (1.0 + fabs(t))) {
        say(s, fmi2Error, "fmi2DoStep: step from t=%g by %g, but the FMU is at t=%g", t, h, s->t);
        return fmi2Error;
    }
    if (h == 0.0) return fmi2OK;
    if (refresh(s) != fmi2OK) return fmi2Error;
    s->d[0] = s->alpha;
    s->d[1] = s->beta;
    for (i = 0; i < NX; i++) s->atol[i] = s->rtol * 1e-2 * NOMINAL[i];
    memset(&st, 0, sizeof st);
    t_end = s->t + h;
    rc = mbrt_dop853(cs_rhs, NULL, s, NX, s->t, s->y, t_end, s->rtol, s->atol, 0.0, 0.0, 0, &t_end, 1,
                     s->y_end, &written, s->work, &st);
    if (rc != MBRT_OK || written != 1) {
        say(s, fmi2Error, "fmi2DoStep from t=%g: %s", s->t, st.message);
        s->mode = M_ERROR;
        return fmi2Error;
    }
    memcpy(s->y, s->y_end, sizeof(double) * NX);
    s->t = t_end;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                   const fmi2Integer order[], const fmi2Real v[])
{ (void)vr; (void)order; (void)v; return n ? unsupported(c, "fmi2SetRealInputDerivatives (no inputs)") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                    const fmi2Integer order[], fmi2Real v[])
{ (void)vr; (void)order; (void)v; return n ? unsupported(c, "fmi2GetRealOutputDerivatives") : fmi2OK; }
FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep (steps are not asynchronous)"); }
FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v)
{
    NEED(c);
    if (k == fmi2DoStepStatus && v) { *v = fmi2OK; return fmi2OK; }
    return unsupported(c, "fmi2GetStatus of this kind");
}
FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v)
{
    NEED(c);
    if (k == fmi2LastSuccessfulTime && v) { *v = ((Inst *)c)->t; return fmi2OK; }
    return unsupported(c, "fmi2GetRealStatus of this kind");
}
FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v)
{ (void)k; (void)v; return unsupported(c, "fmi2GetIntegerStatus"); }
FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v)
{
    NEED(c);
    if (k == fmi2Terminated && v) { *v = 0; return fmi2OK; }
    return unsupported(c, "fmi2GetBooleanStatus of this kind");
}
FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v)
{ (void)k; (void)v; return unsupported(c, "fmi2GetStringStatus"); }
