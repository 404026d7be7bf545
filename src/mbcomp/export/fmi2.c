/* mbcomp FMI 2.0 wrapper (Model Exchange and Co-Simulation) over the FMU core (fmu_core.c,
 * included before this file): the standard's functions, translated into the core's calls.
 * The types below are the standard's ABI, declared here from the FMI 2.0.x specification so
 * the FMU carries no header of anyone else. */
#include "fmu_core.c"

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

static void fmi2_log(Inst *c, int error, const char *msg)
{
    fmi2CallbackLogger logger = (fmi2CallbackLogger)c->logger;
    if (logger) logger(c->env, c->name, error ? fmi2Error : fmi2OK, error ? "logStatusError" : "logAll", "%s", msg);
}

#define NEED(c) do { if (!(c)) return fmi2Error; if (((Inst *)(c))->mode == M_ERROR) return fmi2Error; } while (0)
#define OK(x) ((x) == 0 ? fmi2OK : fmi2Error)
/* NEED, and the call fn allowed in the instance's mode (mask: fmu_rules.c's S_*) */
#define STATE(c, fn, mask) do { NEED(c); if (mb_allowed((Inst *)(c), fn, mask)) return fmi2Error; } while (0)

static fmi2Status unsupported(fmi2Component c, const char *what)
{
    say((Inst *)c, 1, "%s is not supported by this FMU", what);
    return fmi2Error;
}

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
    if (type != fmi2ModelExchange && type != fmi2CoSimulation) return NULL;
    c = mb_new(name, type == fmi2CoSimulation);
    if (!c) return NULL;
    c->logger = (void (*)(void))cb->logger;
    c->env = cb->componentEnvironment;
    c->log = fmi2_log;
    c->logging = logging;
    return c;
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c) { mb_free((Inst *)c); }

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real t0,
                                           fmi2Boolean stopDef, fmi2Real tStop)
{
    (void)stopDef; (void)tStop;
    STATE(c, "fmi2SetupExperiment", S_INST);
    ((Inst *)c)->t = t0;
    if (tolDef) {
        if (!(tol >= 1e-14 && tol < 1.0)) {
            say((Inst *)c, 1, "fmi2SetupExperiment: tolerance %g is out of range (1e-14 .. 1)", tol);
            return fmi2Error;
        }
        if (!((Inst *)c)->tol_set) ((Inst *)c)->rtol = tol;
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    STATE(c, "fmi2EnterInitializationMode", S_INST);
    ((Inst *)c)->mode = M_INIT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    STATE(c, "fmi2ExitInitializationMode", S_INIT);
    if (mb_check_rules((Inst *)c) || mb_refresh((Inst *)c) || mb_start_states((Inst *)c)) return fmi2Error;
    ((Inst *)c)->mode = ((Inst *)c)->cs ? M_STEP : M_EVENT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c)
{
    STATE(c, "fmi2Terminate", S_EVENT | S_CONT | S_STEP);
    ((Inst *)c)->mode = M_TERMINATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    if (!c) return fmi2Error;
    mb_reset((Inst *)c);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    int have = 0;
    STATE(c, "fmi2GetReal", S_INIT | S_EVENT | S_CONT | S_STEP | S_TERM);
    for (i = 0; i < n; i++)
        if (mb_get((Inst *)c, vr[i], &value[i], &have)) return fmi2Error;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    STATE(c, "fmi2SetReal", S_INST | S_INIT | S_EVENT | S_CONT | S_STEP);
    for (i = 0; i < n; i++)
        if (mb_set((Inst *)c, vr[i], value[i])) return fmi2Error;
    return fmi2OK;
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
/* FMU states (fmu_state.c): allowed in every state of the standard's table */
FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{ return c ? OK(mb_state_get((Inst *)c, s)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{ return c ? OK(mb_state_set((Inst *)c, s)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{ return c ? OK(mb_state_free((Inst *)c, s)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{ return c ? OK(mb_state_size((Inst *)c, s, n)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ return c ? OK(mb_state_serialize((Inst *)c, s, (unsigned char *)b, n)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{ return c ? OK(mb_state_deserialize((Inst *)c, (const unsigned char *)b, n, s)) : fmi2Error; }
FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                                    const fmi2ValueReference z[], size_t nz, const fmi2Real du[],
                                                    fmi2Real dz[])
{
    NEED(c); /* u: the unknowns (nu), z: the knowns (nz), du: the knowns' seed, dz: the unknowns' change */
    return OK(mb_derivative((Inst *)c, 0, u, nu, z, nz, du, nz, dz, nu));
}

/* --- Model Exchange ---------------------------------------------------------------------- */
FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    STATE(c, "fmi2EnterEventMode", S_EVENT | S_CONT);
    ((Inst *)c)->mode = M_EVENT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e)
{
    int changed = 0;
    STATE(c, "fmi2NewDiscreteStates", S_EVENT);
    if (!e) return fmi2Error;
    memset(e, 0, sizeof *e);
    if (mb_update((Inst *)c, &changed)) return fmi2Error;
    e->terminateSimulation = mb_ended((Inst *)c) != 0; /* a terminal user event fired */
    e->valuesOfContinuousStatesChanged = changed;
    e->nominalsOfContinuousStatesChanged = changed;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    STATE(c, "fmi2EnterContinuousTimeMode", S_EVENT);
    if (mb_after_end((Inst *)c, "fmi2EnterContinuousTimeMode")) return fmi2Error; /* a terminal event */
    ((Inst *)c)->mode = M_CONT;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePrior,
                                                   fmi2Boolean *enterEventMode, fmi2Boolean *terminate)
{
    int event = 0;
    (void)noSetFMUStatePrior;
    STATE(c, "fmi2CompletedIntegratorStep", S_CONT);
    if (!enterEventMode || !terminate) return fmi2Error;
    if (mb_completed((Inst *)c, &event)) return fmi2Error;
    *enterEventMode = event;
    *terminate = mb_ended((Inst *)c) != 0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t)
{
    STATE(c, "fmi2SetTime", S_EVENT | S_CONT);
    ((Inst *)c)->t = t;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    STATE(c, "fmi2SetContinuousStates", S_CONT);
    return OK(mb_set_x((Inst *)c, x, nx));
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    STATE(c, "fmi2GetDerivatives", S_EVENT | S_CONT | S_TERM);
    return OK(mb_get_dx((Inst *)c, dx, nx));
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz)
{
    STATE(c, "fmi2GetEventIndicators", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_event_indicators((Inst *)c, z, nz));
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    STATE(c, "fmi2GetContinuousStates", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_get_x((Inst *)c, x, nx));
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    STATE(c, "fmi2GetNominalsOfContinuousStates", S_INST | S_EVENT | S_CONT | S_TERM);
    return OK(mb_nominals((Inst *)c, x, nx));
}

/* --- Co-Simulation ----------------------------------------------------------------------- */
FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior)
{
    Inst *s = (Inst *)c;
    (void)noSetPrior;
    NEED(c);
    if (!s->cs) return unsupported(c, "fmi2DoStep in a Model Exchange instance");
    STATE(c, "fmi2DoStep", S_STEP);
    if (fabs(t - s->t) > 1e-9 * (1.0 + fabs(t))) {
        say(s, 1, "fmi2DoStep: a step from t=%g, but the FMU is at t=%g", t, s->t);
        return fmi2Error;
    }
    if (mb_step(s, h)) return fmi2Error;
    return mb_ended(s) ? fmi2Discard : fmi2OK; /* a terminal user event: stopped at it (fmi2LastSuccessfulTime) */
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
    if (k == fmi2Terminated && v) { *v = mb_ended((Inst *)c) != 0; return fmi2OK; }
    return unsupported(c, "fmi2GetBooleanStatus of this kind");
}
FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v)
{ (void)k; (void)v; return unsupported(c, "fmi2GetStringStatus"); }
