/* FMI 2.0 interface of an exported symmech model (Model Exchange and Co-Simulation), written for symmech
   from the FMI 2.0 standard's function signatures; the types below are this file's own minimal declarations
   of what the standard defines. Functions of features the model does not have (integer, boolean and string
   variables, FMU states, directional derivatives, input derivatives, asynchronous steps) return fmi2Error. */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "symmech_model.h"

#if defined(_WIN32)
#define FMI2_EXPORT __declspec(dllexport)
#elif defined(__GNUC__)
#define FMI2_EXPORT __attribute__((visibility("default")))
#else
#define FMI2_EXPORT
#endif

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
typedef struct {
    void (*logger)(fmi2ComponentEnvironment, fmi2String instanceName, fmi2Status, fmi2String category,
                   fmi2String message, ...);
    void *(*allocateMemory)(size_t nobj, size_t size);
    void (*freeMemory)(void *obj);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;

typedef struct {
    SymmechModel model;
    const fmi2CallbackFunctions *callbacks;
    double tolerance;  /* Co-Simulation: relative tolerance of DOP853 */
    double last_time;  /* end of the last successful step */
    int terminated;    /* Co-Simulation: the model ended the simulation (fmi2Terminated) */
} Instance;

static fmi2Status fail(Instance *inst, const char *message)
{
    if (inst && inst->callbacks && inst->callbacks->logger)
        inst->callbacks->logger(inst->callbacks->componentEnvironment, MODEL_IDENTIFIER, fmi2Error,
                                "logStatusError", "%s", message);
    return fmi2Error;
}

/* the model's notices (a rocking contact, the stop at max_impacts) as warnings with their time */
static void notice(void *env, double t, const char *message)
{
    Instance *inst = env;
    if (inst->callbacks && inst->callbacks->logger)
        inst->callbacks->logger(inst->callbacks->componentEnvironment, MODEL_IDENTIFIER, fmi2Warning,
                                "logStatusWarning", "t = %.17g s: %s", t, message);
}

FMI2_EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
FMI2_EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    (void)c; (void)loggingOn; (void)nCategories; (void)categories;
    return fmi2OK;
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                          fmi2Boolean loggingOn)
{
    (void)instanceName; (void)fmuType; (void)fmuResourceLocation; (void)visible; (void)loggingOn;
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_TOKEN) != 0) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "GUID does not match this FMU");
        return NULL;
    }
    Instance *inst = calloc(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->callbacks = functions;
    inst->tolerance = DEFAULT_TOLERANCE;
    symmech_reset(&inst->model);
    inst->model.notice = notice;
    inst->model.notice_env = inst;
    return inst;
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c) { free(c); }

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *inst = c;
    (void)stopTimeDefined; (void)stopTime;
    if (toleranceDefined && tolerance > 0.0) inst->tolerance = tolerance;
    inst->model.r[VR_TIME] = startTime;
    inst->last_time = startTime;
    inst->model.dirty = 1;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *inst = c;
    if (symmech_start(&inst->model) != 0) return fail(inst, "singular M or non-finite rates at the start");
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *inst = c;
    symmech_reset(&inst->model);
    inst->tolerance = DEFAULT_TOLERANCE;
    inst->terminated = 0;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    Instance *inst = c;
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_REAL) return fail(inst, "fmi2GetReal: unknown value reference");
        value[i] = inst->model.r[vr[i]];
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[])
{
    Instance *inst = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= N_REAL || vr[i] == VR_TIME || (vr[i] >= VR_DX && vr[i] < VR_U) || vr[i] >= VR_D)
            return fail(inst, "fmi2SetReal: not an input, parameter or state");
        inst->model.r[vr[i]] = value[i];
    }
    inst->model.dirty = 1;
    return fmi2OK;
}

/* Model Exchange */

FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    Instance *inst = c;
    int changed = symmech_event_update(&inst->model);
    memset(info, 0, sizeof *info);
    info->valuesOfContinuousStatesChanged = changed == 1;
    info->terminateSimulation = changed == SYMMECH_STOP;
    return changed < 0 ? fail(inst, "fmi2NewDiscreteStates: non-finite state at the event") : fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    Instance *inst = c;
    (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = 0;
    *terminateSimulation = symmech_left_model(&inst->model);
    return *terminateSimulation ? fail(inst, LEFT_MODEL_MESSAGE)
                                : fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    Instance *inst = c;
    inst->model.r[VR_TIME] = time;
    inst->model.dirty = 1;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Instance *inst = c;
    if (nx != N_X) return fail(inst, "fmi2SetContinuousStates: wrong number of states");
    memcpy(inst->model.r + VR_X, x, N_X * sizeof(double));
    inst->model.dirty = 1;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    Instance *inst = c;
    if (nx != N_X) return fail(inst, "fmi2GetContinuousStates: wrong number of states");
    memcpy(x, inst->model.r + VR_X, N_X * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    Instance *inst = c;
    if (nx != N_X) return fail(inst, "fmi2GetDerivatives: wrong number of states");
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    memcpy(derivatives, inst->model.dx, N_X * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    Instance *inst = c;
    if (ni != N_Z) return fail(inst, "fmi2GetEventIndicators: wrong number of event indicators");
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    if (N_Z > 0) memcpy(eventIndicators, inst->model.r + VR_Z, N_Z * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    static const double nominal[N_X] = NOMINALS;
    if (nx != N_X) return fail(c, "wrong number of states");
    memcpy(x_nominal, nominal, sizeof nominal);
    return fmi2OK;
}

/* Co-Simulation */

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance *inst = c;
    (void)noSetFMUStatePriorToCurrentPoint;
    inst->model.r[VR_TIME] = currentCommunicationPoint;
    int status = symmech_integrate(&inst->model, currentCommunicationPoint + communicationStepSize,
                                   inst->tolerance, ABSOLUTE_TOLERANCE * inst->tolerance);
    inst->last_time = inst->model.r[VR_TIME];
    if (status == 1) {  /* the model ended the simulation at last_time (its notice logged) */
        inst->terminated = 1;
        return fmi2Discard;
    }
    if (status == -2)
        return fail(inst, "fmi2DoStep: " LEFT_MODEL_MESSAGE);
    return status == 0 ? fmi2OK : fail(inst, "fmi2DoStep: the integration failed (singular M or non-finite state)");
}

FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) { return fail(c, "fmi2CancelStep: steps are synchronous"); }

FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *inst = c;
    if (s != fmi2LastSuccessfulTime) return fail(inst, "fmi2GetRealStatus: only fmi2LastSuccessfulTime");
    *value = inst->last_time;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    Instance *inst = c;
    if (s != fmi2Terminated) return fail(inst, "fmi2GetBooleanStatus: only fmi2Terminated");
    *value = inst->terminated;
    return fmi2OK;
}

/* ---- features the model does not have ---- */

#define UNSUPPORTED(name, ...) \
    FMI2_EXPORT fmi2Status name(fmi2Component c, __VA_ARGS__) { return fail(c, #name " is not supported"); }

UNSUPPORTED(fmi2GetInteger, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
UNSUPPORTED(fmi2GetBoolean, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
UNSUPPORTED(fmi2GetString, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
UNSUPPORTED(fmi2SetInteger, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
UNSUPPORTED(fmi2SetBoolean, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
UNSUPPORTED(fmi2SetString, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
UNSUPPORTED(fmi2GetFMUstate, fmi2FMUstate *state)
UNSUPPORTED(fmi2SetFMUstate, fmi2FMUstate state)
UNSUPPORTED(fmi2FreeFMUstate, fmi2FMUstate *state)
UNSUPPORTED(fmi2SerializedFMUstateSize, fmi2FMUstate state, size_t *size)
UNSUPPORTED(fmi2SerializeFMUstate, fmi2FMUstate state, fmi2Byte serializedState[], size_t size)
UNSUPPORTED(fmi2DeSerializeFMUstate, const fmi2Byte serializedState[], size_t size, fmi2FMUstate *state)
UNSUPPORTED(fmi2GetDirectionalDerivative, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
            const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[])
UNSUPPORTED(fmi2SetRealInputDerivatives, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
            const fmi2Real value[])
UNSUPPORTED(fmi2GetRealOutputDerivatives, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],
            fmi2Real value[])
UNSUPPORTED(fmi2GetStatus, const fmi2StatusKind s, fmi2Status *value)
UNSUPPORTED(fmi2GetIntegerStatus, const fmi2StatusKind s, fmi2Integer *value)
UNSUPPORTED(fmi2GetStringStatus, const fmi2StatusKind s, fmi2String *value)
