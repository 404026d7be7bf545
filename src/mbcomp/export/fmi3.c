/* mbcomp FMI 3.0 wrapper (Model Exchange and Co-Simulation) over the FMU core (fmu_core.c,
 * included before this file): the standard's functions, translated into the core's calls.
 * The types below are the standard's ABI, declared here from the FMI 3.0 specification so the
 * FMU carries no header of anyone else. Scheduled Execution, clocks and every non-Float64
 * type are not supported: those functions log and return
 * fmi3Error (a call with no variables is fine). */
#include <stdbool.h>
#include <stdint.h>

#define MB_EARLY_RETURN 1 /* fmi3DoStep may return early (a terminal user event: fmu_user_events.c) */
#include "fmu_core.c"

typedef void *fmi3Instance;
typedef void *fmi3InstanceEnvironment;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef float fmi3Float32;
typedef double fmi3Float64;
typedef int8_t fmi3Int8;
typedef uint8_t fmi3UInt8;
typedef int16_t fmi3Int16;
typedef uint16_t fmi3UInt16;
typedef int32_t fmi3Int32;
typedef uint32_t fmi3UInt32;
typedef int64_t fmi3Int64;
typedef uint64_t fmi3UInt64;
typedef bool fmi3Boolean;
typedef char fmi3Char;
typedef const fmi3Char *fmi3String;
typedef uint8_t fmi3Byte;
typedef const fmi3Byte *fmi3Binary;
typedef bool fmi3Clock;
typedef enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal } fmi3Status;
typedef enum { fmi3Independent, fmi3Constant, fmi3Fixed, fmi3Tunable, fmi3Discrete, fmi3Dependent } fmi3DependencyKind;
typedef enum { fmi3IntervalNotYetKnown, fmi3IntervalUnchanged, fmi3IntervalChanged } fmi3IntervalQualifier;
typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String);
typedef void (*fmi3ClockUpdateCallback)(fmi3InstanceEnvironment);
typedef void (*fmi3IntermediateUpdateCallback)(fmi3InstanceEnvironment, fmi3Float64, fmi3Boolean, fmi3Boolean,
                                               fmi3Boolean, fmi3Boolean, fmi3Boolean *, fmi3Float64 *);
typedef void (*fmi3LockPreemptionCallback)(void);
typedef void (*fmi3UnlockPreemptionCallback)(void);

#if defined(__GNUC__)
#define FMI3_EXPORT __attribute__((visibility("default")))
#else
#define FMI3_EXPORT
#endif

static void fmi3_log(Inst *c, int error, const char *msg)
{
    fmi3LogMessageCallback logger = (fmi3LogMessageCallback)c->logger;
    if (logger) logger(c->env, error ? fmi3Error : fmi3OK, error ? "logStatusError" : "logEvents", msg);
}

#define NEED(c) do { if (!(c)) return fmi3Error; if (((Inst *)(c))->mode == M_ERROR) return fmi3Error; } while (0)
#define OK(x) ((x) == 0 ? fmi3OK : fmi3Error)
/* NEED, and the call fn allowed in the instance's mode (mask: fmu_rules.c's S_*) */
#define STATE(c, fn, mask) do { NEED(c); if (mb_allowed((Inst *)(c), fn, mask)) return fmi3Error; } while (0)

static fmi3Status unsupported(fmi3Instance c, const char *what)
{
    say((Inst *)c, 1, "%s is not supported by this FMU", what);
    return fmi3Error;
}

static Inst *instantiate(fmi3String name, fmi3String token, fmi3Boolean logging, fmi3InstanceEnvironment env,
                         fmi3LogMessageCallback logMessage, int cs)
{
    Inst *c;
    if (!name || !token || strcmp(token, GUID) != 0) {
        if (logMessage) {
            char msg[256];
            snprintf(msg, sizeof msg, "wrong instantiation token %s: this FMU's is %s (the model description and "
                     "the binary must match)", token ? token : "(null)", GUID);
            logMessage(env, fmi3Error, "logStatusError", msg);
        }
        return NULL;
    }
    c = mb_new(name, cs);
    if (!c) return NULL;
    c->logger = (void (*)(void))logMessage;
    c->env = env;
    c->log = fmi3_log;
    c->logging = logging;
    return c;
}

FMI3_EXPORT const char *fmi3GetVersion(void) { return "3.0"; }

FMI3_EXPORT fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[])
{
    (void)n; (void)cats;
    if (!c) return fmi3Error;
    ((Inst *)c)->logging = on;
    return fmi3OK;
}

FMI3_EXPORT fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                                      fmi3Boolean visible, fmi3Boolean logging,
                                                      fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage)
{
    (void)resources; (void)visible;
    return instantiate(name, token, logging, env, logMessage, 0);
}

FMI3_EXPORT fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                                     fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean eventMode,
                                                     fmi3Boolean earlyReturn, const fmi3ValueReference required[],
                                                     size_t nRequired, fmi3InstanceEnvironment env,
                                                     fmi3LogMessageCallback logMessage,
                                                     fmi3IntermediateUpdateCallback intermediateUpdate)
{
    fmi3Instance s;
    (void)resources; (void)visible; (void)required; (void)nRequired; (void)intermediateUpdate;
    if (eventMode) {  /* the FMU declares hasEventMode="false" */
        if (logMessage) logMessage(env, fmi3Error, "logStatusError", "event mode is not supported by this FMU");
        return NULL;
    }
    s = instantiate(name, token, logging, env, logMessage, 1);
    if (s) mb_allow_early((Inst *)s, earlyReturn); /* a terminal user event's step returns early at it */
    return s;
}

FMI3_EXPORT fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
                                                           fmi3Boolean visible, fmi3Boolean logging,
                                                           fmi3InstanceEnvironment env,
                                                           fmi3LogMessageCallback logMessage,
                                                           fmi3ClockUpdateCallback clockUpdate,
                                                           fmi3LockPreemptionCallback lock,
                                                           fmi3UnlockPreemptionCallback unlock)
{
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)clockUpdate; (void)lock;
    (void)unlock;
    if (logMessage) logMessage(env, fmi3Error, "logStatusError", "Scheduled Execution is not supported by this FMU");
    return NULL;
}

FMI3_EXPORT void fmi3FreeInstance(fmi3Instance c) { mb_free((Inst *)c); }

FMI3_EXPORT fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolDef, fmi3Float64 tol,
                                                   fmi3Float64 t0, fmi3Boolean stopDef, fmi3Float64 tStop)
{
    Inst *s = (Inst *)c;
    (void)stopDef; (void)tStop;
    STATE(c, "fmi3EnterInitializationMode", S_INST);
    s->t = t0;
    if (tolDef) {
        if (!(tol >= 1e-14 && tol < 1.0)) {
            say(s, 1, "fmi3EnterInitializationMode: tolerance %g is out of range (1e-14 .. 1)", tol);
            return fmi3Error;
        }
        if (!s->tol_set) s->rtol = tol;
    }
    s->mode = M_INIT;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3ExitInitializationMode(fmi3Instance c)
{
    STATE(c, "fmi3ExitInitializationMode", S_INIT);
    if (mb_check_rules((Inst *)c) || mb_refresh((Inst *)c) || mb_start_states((Inst *)c)) return fmi3Error;
    ((Inst *)c)->mode = ((Inst *)c)->cs ? M_STEP : M_EVENT;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3EnterEventMode(fmi3Instance c)
{
    STATE(c, "fmi3EnterEventMode", S_EVENT | S_CONT);
    ((Inst *)c)->mode = M_EVENT;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3Terminate(fmi3Instance c)
{
    STATE(c, "fmi3Terminate", S_EVENT | S_CONT | S_STEP);
    ((Inst *)c)->mode = M_TERMINATED;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3Reset(fmi3Instance c)
{
    if (!c) return fmi3Error;
    mb_reset((Inst *)c);
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 v[],
                                      size_t nv)
{
    size_t i;
    int have = 0;
    STATE(c, "fmi3GetFloat64", S_INIT | S_EVENT | S_CONT | S_STEP | S_TERM);
    if (nv < nvr) { say((Inst *)c, 1, "fmi3GetFloat64: %zu values for %zu variables", nv, nvr); return fmi3Error; }
    for (i = 0; i < nvr; i++)
        if (mb_get((Inst *)c, vr[i], &v[i], &have)) return fmi3Error;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                      const fmi3Float64 v[], size_t nv)
{
    size_t i;
    STATE(c, "fmi3SetFloat64", S_ANY);
    if (nv < nvr) { say((Inst *)c, 1, "fmi3SetFloat64: %zu values for %zu variables", nv, nvr); return fmi3Error; }
    for (i = 0; i < nvr; i++)
        if (mb_set((Inst *)c, vr[i], v[i])) return fmi3Error;
    return fmi3OK;
}

/* the variable types this FMU has none of: nothing to get or set */
#define NONE_OF(T, NAME)                                                                                        \
    FMI3_EXPORT fmi3Status fmi3Get##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, T v[],      \
                                         size_t nv)                                                             \
    { (void)vr; (void)v; (void)nv; return nvr ? unsupported(c, "fmi3Get" #NAME " (no such variables)") : fmi3OK; } \
    FMI3_EXPORT fmi3Status fmi3Set##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const T v[], \
                                         size_t nv)                                                             \
    { (void)vr; (void)v; (void)nv; return nvr ? unsupported(c, "fmi3Set" #NAME " (no such variables)") : fmi3OK; }
NONE_OF(fmi3Float32, Float32)
NONE_OF(fmi3Int8, Int8)
NONE_OF(fmi3UInt8, UInt8)
NONE_OF(fmi3Int16, Int16)
NONE_OF(fmi3UInt16, UInt16)
NONE_OF(fmi3Int32, Int32)
NONE_OF(fmi3UInt32, UInt32)
NONE_OF(fmi3Int64, Int64)
NONE_OF(fmi3UInt64, UInt64)
NONE_OF(fmi3Boolean, Boolean)
NONE_OF(fmi3String, String)

FMI3_EXPORT fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, size_t sizes[],
                                     fmi3Binary v[], size_t nv)
{ (void)vr; (void)sizes; (void)v; (void)nv; return nvr ? unsupported(c, "fmi3GetBinary (no such variables)") : fmi3OK; }
FMI3_EXPORT fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[],
                                     const fmi3Binary v[], size_t nv)
{ (void)vr; (void)sizes; (void)v; (void)nv; return nvr ? unsupported(c, "fmi3SetBinary (no such variables)") : fmi3OK; }
FMI3_EXPORT fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock v[])
{ (void)vr; (void)v; return nvr ? unsupported(c, "fmi3GetClock (no clocks)") : fmi3OK; }
FMI3_EXPORT fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock v[])
{ (void)vr; (void)v; return nvr ? unsupported(c, "fmi3SetClock (no clocks)") : fmi3OK; }

FMI3_EXPORT fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr, size_t *n)
{ (void)vr; (void)n; return unsupported(c, "fmi3GetNumberOfVariableDependencies"); }
FMI3_EXPORT fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dep, size_t ed[],
                                                   fmi3ValueReference ind[], size_t ei[], fmi3DependencyKind k[],
                                                   size_t n)
{ (void)dep; (void)ed; (void)ind; (void)ei; (void)k; (void)n; return unsupported(c, "fmi3GetVariableDependencies"); }
/* FMU states (fmu_state.c): allowed in every mode, as the standard's state table has it */
FMI3_EXPORT fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s)
{ return c ? OK(mb_state_get((Inst *)c, s)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s)
{ return c ? OK(mb_state_set((Inst *)c, s)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s)
{ return c ? OK(mb_state_free((Inst *)c, s)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *n)
{ return c ? OK(mb_state_size((Inst *)c, s, n)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte b[], size_t n)
{ return c ? OK(mb_state_serialize((Inst *)c, s, b, n)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte b[], size_t n, fmi3FMUState *s)
{ return c ? OK(mb_state_deserialize((Inst *)c, b, n, s)) : fmi3Error; }
FMI3_EXPORT fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                                    const fmi3ValueReference k[], size_t nk, const fmi3Float64 seed[],
                                                    size_t ns, fmi3Float64 sens[], size_t nsens)
{
    NEED(c);
    return OK(mb_derivative((Inst *)c, 0, u, nu, k, nk, seed, ns, sens, nsens));
}
FMI3_EXPORT fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                                const fmi3ValueReference k[], size_t nk, const fmi3Float64 seed[],
                                                size_t ns, fmi3Float64 sens[], size_t nsens)
{
    NEED(c);
    return OK(mb_derivative((Inst *)c, 1, u, nu, k, nk, seed, ns, sens, nsens));
}
FMI3_EXPORT fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3EnterConfigurationMode"); }
FMI3_EXPORT fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3ExitConfigurationMode"); }
FMI3_EXPORT fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                              fmi3Float64 iv[], fmi3IntervalQualifier q[])
{ (void)vr; (void)n; (void)iv; (void)q; return unsupported(c, "fmi3GetIntervalDecimal (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                               fmi3UInt64 cnt[], fmi3UInt64 res[], fmi3IntervalQualifier q[])
{ (void)vr; (void)n; (void)cnt; (void)res; (void)q; return unsupported(c, "fmi3GetIntervalFraction (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 sh[])
{ (void)vr; (void)n; (void)sh; return unsupported(c, "fmi3GetShiftDecimal (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3UInt64 cnt[],
                                            fmi3UInt64 res[])
{ (void)vr; (void)n; (void)cnt; (void)res; return unsupported(c, "fmi3GetShiftFraction (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                              const fmi3Float64 iv[])
{ (void)vr; (void)n; (void)iv; return unsupported(c, "fmi3SetIntervalDecimal (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                               const fmi3UInt64 cnt[], const fmi3UInt64 res[])
{ (void)vr; (void)n; (void)cnt; (void)res; return unsupported(c, "fmi3SetIntervalFraction (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                           const fmi3Float64 sh[])
{ (void)vr; (void)n; (void)sh; return unsupported(c, "fmi3SetShiftDecimal (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                            const fmi3UInt64 cnt[], const fmi3UInt64 res[])
{ (void)vr; (void)n; (void)cnt; (void)res; return unsupported(c, "fmi3SetShiftFraction (no clocks)"); }
FMI3_EXPORT fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c)
{
    NEED(c);
    return fmi3OK;  /* no discrete states */
}

FMI3_EXPORT fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *update, fmi3Boolean *terminate,
                                                fmi3Boolean *nominalsChanged, fmi3Boolean *valuesChanged,
                                                fmi3Boolean *nextDefined, fmi3Float64 *next)
{
    int changed = 0;
    STATE(c, "fmi3UpdateDiscreteStates", S_EVENT);
    if (mb_update((Inst *)c, &changed)) return fmi3Error;
    if (update) *update = false;
    if (terminate) *terminate = mb_ended((Inst *)c) != 0; /* a terminal user event fired */
    if (nominalsChanged) *nominalsChanged = changed;
    if (valuesChanged) *valuesChanged = changed;
    if (nextDefined) *nextDefined = false;
    if (next) *next = 0.0;
    return fmi3OK;
}

/* --- Model Exchange ---------------------------------------------------------------------- */
FMI3_EXPORT fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c)
{
    STATE(c, "fmi3EnterContinuousTimeMode", S_EVENT);
    if (mb_after_end((Inst *)c, "fmi3EnterContinuousTimeMode")) return fmi3Error; /* a terminal event */
    ((Inst *)c)->mode = M_CONT;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetPrior, fmi3Boolean *enterEventMode,
                                                   fmi3Boolean *terminate)
{
    int event = 0;
    (void)noSetPrior;
    STATE(c, "fmi3CompletedIntegratorStep", S_CONT);
    if (!enterEventMode || !terminate) return fmi3Error;
    if (mb_completed((Inst *)c, &event)) return fmi3Error;
    *enterEventMode = event;
    *terminate = mb_ended((Inst *)c) != 0;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t)
{
    STATE(c, "fmi3SetTime", S_EVENT | S_CONT);
    ((Inst *)c)->t = t;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx)
{
    STATE(c, "fmi3SetContinuousStates", S_CONT);
    return OK(mb_set_x((Inst *)c, x, nx));
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx)
{
    STATE(c, "fmi3GetContinuousStateDerivatives", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_get_dx((Inst *)c, dx, nx));
}

FMI3_EXPORT fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t nz)
{
    STATE(c, "fmi3GetEventIndicators", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_event_indicators((Inst *)c, z, nz));
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx)
{
    STATE(c, "fmi3GetContinuousStates", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_get_x((Inst *)c, x, nx));
}

FMI3_EXPORT fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx)
{
    STATE(c, "fmi3GetNominalsOfContinuousStates", S_INIT | S_EVENT | S_CONT | S_TERM);
    return OK(mb_nominals((Inst *)c, x, nx));
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n)
{
    NEED(c);
    if (!n) return fmi3Error;
    *n = MB_NZ;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n)
{
    NEED(c);
    if (!n) return fmi3Error;
    *n = NXS;
    return fmi3OK;
}

/* --- Co-Simulation ----------------------------------------------------------------------- */
FMI3_EXPORT fmi3Status fmi3EnterStepMode(fmi3Instance c)
{
    STATE(c, "fmi3EnterStepMode", S_INIT | S_EVENT);
    ((Inst *)c)->mode = M_STEP;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                                const fmi3Int32 orders[], fmi3Float64 v[], size_t nv)
{ (void)vr; (void)orders; (void)v; (void)nv; return nvr ? unsupported(c, "fmi3GetOutputDerivatives") : fmi3OK; }

FMI3_EXPORT fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                                  fmi3Float64 *lastSuccessfulTime)
{
    Inst *s = (Inst *)c;
    int rc;
    (void)noSetPrior;
    NEED(c);
    if (!s->cs) return unsupported(c, "fmi3DoStep in a Model Exchange instance");
    STATE(c, "fmi3DoStep", S_STEP);
    if (fabs(t - s->t) > 1e-9 * (1.0 + fabs(t))) {
        say(s, 1, "fmi3DoStep: a step from t=%g, but the FMU is at t=%g", t, s->t);
        return fmi3Error;
    }
    rc = mb_step(s, h);
    if (eventHandlingNeeded) *eventHandlingNeeded = false;
    if (terminate) *terminate = !rc && mb_ended(s); /* a terminal user event: the step stopped at it */
    if (earlyReturn) *earlyReturn = !rc && mb_early_return(s);
    if (lastSuccessfulTime) *lastSuccessfulTime = s->t;
    return OK(rc);
}

/* --- Scheduled Execution ------------------------------------------------------------------ */
FMI3_EXPORT fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clock, fmi3Float64 t)
{ (void)clock; (void)t; return unsupported(c, "fmi3ActivateModelPartition (Scheduled Execution)"); }
