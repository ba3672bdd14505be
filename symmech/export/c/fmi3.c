/* FMI 3.0 interface of an exported symmech model (Model Exchange and Co-Simulation), written for symmech
   from the FMI 3.0 standard's function signatures; the types below are this file's own minimal declarations
   of what the standard defines. Functions of features the model does not have (clocks, other variable types,
   FMU states, directional derivatives) exist because importers bind every symbol, and return fmi3Error. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "symmech_model.h"

#if defined(_WIN32)
#define FMI3_EXPORT __declspec(dllexport)
#elif defined(__GNUC__)
#define FMI3_EXPORT __attribute__((visibility("default")))
#else
#define FMI3_EXPORT
#endif

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
typedef enum { fmi3Independent, fmi3Dependent, fmi3Constant, fmi3Fixed, fmi3Tunable, fmi3Discrete } fmi3DependencyKind;
typedef enum { fmi3IntervalNotYetKnown, fmi3IntervalUnchanged, fmi3IntervalChanged } fmi3IntervalQualifier;
typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status, fmi3String category, fmi3String message);
typedef void (*fmi3IntermediateUpdateCallback)(fmi3InstanceEnvironment, fmi3Float64, fmi3Boolean, fmi3Boolean,
                                               fmi3Boolean, fmi3Boolean, fmi3Boolean *, fmi3Float64 *);
typedef void (*fmi3ClockUpdateCallback)(fmi3InstanceEnvironment);
typedef void (*fmi3LockPreemptionCallback)(void);
typedef void (*fmi3UnlockPreemptionCallback)(void);

typedef struct {
    SymmechModel model;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    double tolerance;  /* Co-Simulation: relative tolerance of DOP853 */
    bool early_return_allowed;  /* Co-Simulation: fmi3DoStep may return before the step's end */
} Instance;

static fmi3Status fail(Instance *inst, const char *message)
{
    if (inst && inst->log) inst->log(inst->environment, fmi3Error, "logStatusError", message);
    return fmi3Error;
}

/* the model's notices (a rocking contact, the stop at max_impacts) as warnings with their time */
static void notice(void *env, double t, const char *message)
{
    Instance *inst = env;
    char line[512];
    snprintf(line, sizeof line, "t = %.17g s: %s", t, message);
    if (inst->log) inst->log(inst->environment, fmi3Warning, "logStatusWarning", line);
}

static Instance *instantiate(fmi3String token, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log)
{
    if (token == NULL || strcmp(token, MODEL_TOKEN) != 0) {
        if (log) log(environment, fmi3Error, "logStatusError", "instantiation token does not match this FMU");
        return NULL;
    }
    Instance *inst = calloc(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->environment = environment;
    inst->log = log;
    inst->tolerance = DEFAULT_TOLERANCE;
    symmech_reset(&inst->model);
    inst->model.notice = notice;
    inst->model.notice_env = inst;
    return inst;
}

FMI3_EXPORT const char *fmi3GetVersion(void) { return "3.0"; }

FMI3_EXPORT fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[])
{
    (void)instance; (void)loggingOn; (void)nCategories; (void)categories;
    return fmi3OK;
}

FMI3_EXPORT fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                                      fmi3LogMessageCallback logMessage)
{
    (void)instanceName; (void)resourcePath; (void)visible; (void)loggingOn;
    return instantiate(instantiationToken, environment, logMessage);
}

FMI3_EXPORT fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                                     fmi3String resourcePath, fmi3Boolean visible,
                                                     fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                                     fmi3Boolean earlyReturnAllowed,
                                                     const fmi3ValueReference requiredIntermediateVariables[],
                                                     size_t nRequiredIntermediateVariables,
                                                     fmi3InstanceEnvironment environment,
                                                     fmi3LogMessageCallback logMessage,
                                                     fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)instanceName; (void)resourcePath; (void)visible; (void)loggingOn; (void)eventModeUsed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
    Instance *inst = instantiate(instantiationToken, environment, logMessage);
    if (inst != NULL) inst->early_return_allowed = earlyReturnAllowed;
    return inst;
}

FMI3_EXPORT fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                                           fmi3String resourcePath, fmi3Boolean visible,
                                                           fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                                           fmi3LogMessageCallback logMessage,
                                                           fmi3ClockUpdateCallback clockUpdate,
                                                           fmi3LockPreemptionCallback lockPreemption,
                                                           fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage) logMessage(environment, fmi3Error, "logStatusError", "scheduled execution is not supported");
    return NULL;
}

FMI3_EXPORT void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

FMI3_EXPORT fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Instance *inst = instance;
    (void)stopTimeDefined; (void)stopTime;
    if (toleranceDefined && tolerance > 0.0) inst->tolerance = tolerance;
    inst->model.r[VR_TIME] = startTime;
    inst->model.dirty = 1;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance *inst = instance;
    if (symmech_start(&inst->model) != 0) return fail(inst, "singular M or non-finite rates at the start");
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3EnterEventMode(fmi3Instance instance) { (void)instance; return fmi3OK; }
FMI3_EXPORT fmi3Status fmi3Terminate(fmi3Instance instance) { (void)instance; return fmi3OK; }

FMI3_EXPORT fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance *inst = instance;
    symmech_reset(&inst->model);
    inst->tolerance = DEFAULT_TOLERANCE;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                      size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    Instance *inst = instance;
    if (nValues != nValueReferences) return fail(inst, "fmi3GetFloat64: one value per value reference");
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    for (size_t i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] >= N_REAL) return fail(inst, "fmi3GetFloat64: unknown value reference");
        values[i] = inst->model.r[valueReferences[i]];
    }
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                      size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    Instance *inst = instance;
    if (nValues != nValueReferences) return fail(inst, "fmi3SetFloat64: one value per value reference");
    for (size_t i = 0; i < nValueReferences; i++) {
        fmi3ValueReference vr = valueReferences[i];
        if (vr >= N_REAL || vr == VR_TIME || (vr >= VR_DX && vr < VR_U) || vr >= VR_D)
            return fail(inst, "fmi3SetFloat64: not an input, parameter or state");
        inst->model.r[vr] = values[i];
    }
    inst->model.dirty = 1;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    Instance *inst = instance;
    int changed = symmech_event_update(&inst->model);
    *discreteStatesNeedUpdate = *nominalsOfContinuousStatesChanged = false;
    *terminateSimulation = changed == SYMMECH_STOP;
    *valuesOfContinuousStatesChanged = changed == 1;
    *nextEventTimeDefined = false;
    *nextEventTime = 0.0;
    return changed < 0 ? fail(inst, "fmi3UpdateDiscreteStates: non-finite state at the event") : fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) { (void)instance; return fmi3OK; }

FMI3_EXPORT fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    Instance *inst = instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = false;
    *terminateSimulation = symmech_left_model(&inst->model);
    return *terminateSimulation ? fail(inst, LEFT_MODEL_MESSAGE)
                                : fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    Instance *inst = instance;
    inst->model.r[VR_TIME] = time;
    inst->model.dirty = 1;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates)
{
    Instance *inst = instance;
    if (nContinuousStates != N_X) return fail(inst, "fmi3SetContinuousStates: wrong number of states");
    memcpy(inst->model.r + VR_X, continuousStates, N_X * sizeof(double));
    inst->model.dirty = 1;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                               size_t nContinuousStates)
{
    Instance *inst = instance;
    if (nContinuousStates != N_X) return fail(inst, "fmi3GetContinuousStates: wrong number of states");
    memcpy(continuousStates, inst->model.r + VR_X, N_X * sizeof(double));
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                                         size_t nContinuousStates)
{
    Instance *inst = instance;
    if (nContinuousStates != N_X) return fail(inst, "fmi3GetContinuousStateDerivatives: wrong number of states");
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    memcpy(derivatives, inst->model.dx, N_X * sizeof(double));
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                              size_t nEventIndicators)
{
    Instance *inst = instance;
    if (nEventIndicators != N_Z) return fail(inst, "fmi3GetEventIndicators: wrong number of event indicators");
    if (symmech_derivatives(&inst->model) != 0) return fail(inst, "singular mass matrix or non-finite rates");
    if (N_Z > 0) memcpy(eventIndicators, inst->model.r + VR_Z, N_Z * sizeof(double));
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                                         size_t nContinuousStates)
{
    static const double nominal[N_X] = NOMINALS;
    if (nContinuousStates != N_X) return fail(instance, "wrong number of states");
    memcpy(nominals, nominal, sizeof nominal);
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    (void)instance;
    *nEventIndicators = N_Z;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    (void)instance;
    *nContinuousStates = N_X;
    return fmi3OK;
}

FMI3_EXPORT fmi3Status fmi3EnterStepMode(fmi3Instance instance) { (void)instance; return fmi3OK; }

FMI3_EXPORT fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Instance *inst = instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = false;
    inst->model.r[VR_TIME] = currentCommunicationPoint;
    int status = symmech_integrate(&inst->model, currentCommunicationPoint + communicationStepSize,
                                   inst->tolerance, ABSOLUTE_TOLERANCE * inst->tolerance);
    *lastSuccessfulTime = inst->model.r[VR_TIME];
    if (status == 1) {  /* the model ended the simulation at lastSuccessfulTime (its notice logged) */
        *terminateSimulation = true;
        *earlyReturn = inst->early_return_allowed;
        return fmi3OK;
    }
    if (status == -2) {
        *terminateSimulation = true;
        return fail(inst, "fmi3DoStep: " LEFT_MODEL_MESSAGE);
    }
    if (status != 0) return fail(inst, "fmi3DoStep: the integration failed (singular M or non-finite state)");
    return fmi3OK;
}

/* ---- features the model does not have ---- */

#define UNSUPPORTED(name, ...) \
    FMI3_EXPORT fmi3Status name(fmi3Instance instance, __VA_ARGS__) \
    { return fail(instance, #name " is not supported"); }
#define UNSUPPORTED_TYPE(T) \
    UNSUPPORTED(fmi3Get##T, const fmi3ValueReference vr[], size_t nvr, fmi3##T values[], size_t nValues) \
    UNSUPPORTED(fmi3Set##T, const fmi3ValueReference vr[], size_t nvr, const fmi3##T values[], size_t nValues)

UNSUPPORTED_TYPE(Float32)
UNSUPPORTED_TYPE(Int8)
UNSUPPORTED_TYPE(UInt8)
UNSUPPORTED_TYPE(Int16)
UNSUPPORTED_TYPE(UInt16)
UNSUPPORTED_TYPE(Int32)
UNSUPPORTED_TYPE(UInt32)
UNSUPPORTED_TYPE(Int64)
UNSUPPORTED_TYPE(UInt64)
UNSUPPORTED_TYPE(Boolean)
UNSUPPORTED_TYPE(String)
UNSUPPORTED(fmi3GetBinary, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[], fmi3Binary values[],
            size_t nValues)
UNSUPPORTED(fmi3SetBinary, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
            const fmi3Binary values[], size_t nValues)
UNSUPPORTED(fmi3GetClock, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
UNSUPPORTED(fmi3SetClock, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[])
UNSUPPORTED(fmi3GetNumberOfVariableDependencies, fmi3ValueReference vr, size_t *nDependencies)
UNSUPPORTED(fmi3GetVariableDependencies, fmi3ValueReference dependent, size_t elementIndicesOfDependent[],
            fmi3ValueReference independents[], size_t elementIndicesOfIndependents[],
            fmi3DependencyKind dependencyKinds[], size_t nDependencies)
UNSUPPORTED(fmi3GetFMUState, fmi3FMUState *state)
UNSUPPORTED(fmi3SetFMUState, fmi3FMUState state)
UNSUPPORTED(fmi3FreeFMUState, fmi3FMUState *state)
UNSUPPORTED(fmi3SerializedFMUStateSize, fmi3FMUState state, size_t *size)
UNSUPPORTED(fmi3SerializeFMUState, fmi3FMUState state, fmi3Byte serializedState[], size_t size)
UNSUPPORTED(fmi3DeserializeFMUState, const fmi3Byte serializedState[], size_t size, fmi3FMUState *state)
UNSUPPORTED(fmi3GetDirectionalDerivative, const fmi3ValueReference unknowns[], size_t nUnknowns,
            const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
            fmi3Float64 sensitivity[], size_t nSensitivity)
UNSUPPORTED(fmi3GetAdjointDerivative, const fmi3ValueReference unknowns[], size_t nUnknowns,
            const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
            fmi3Float64 sensitivity[], size_t nSensitivity)
UNSUPPORTED(fmi3GetIntervalDecimal, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 intervals[],
            fmi3IntervalQualifier qualifiers[])
UNSUPPORTED(fmi3GetIntervalFraction, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
            fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
UNSUPPORTED(fmi3GetShiftDecimal, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[])
UNSUPPORTED(fmi3GetShiftFraction, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
            fmi3UInt64 resolutions[])
UNSUPPORTED(fmi3SetIntervalDecimal, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 intervals[])
UNSUPPORTED(fmi3SetIntervalFraction, const fmi3ValueReference vr[], size_t nvr, const fmi3UInt64 counters[],
            const fmi3UInt64 resolutions[])
UNSUPPORTED(fmi3SetShiftDecimal, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 shifts[])
UNSUPPORTED(fmi3SetShiftFraction, const fmi3ValueReference vr[], size_t nvr, const fmi3UInt64 counters[],
            const fmi3UInt64 resolutions[])
UNSUPPORTED(fmi3GetOutputDerivatives, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
            fmi3Float64 values[], size_t nValues)
UNSUPPORTED(fmi3ActivateModelPartition, fmi3ValueReference clockReference, fmi3Float64 activationTime)

FMI3_EXPORT fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return fail(instance, "no configuration mode");
}

FMI3_EXPORT fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return fail(instance, "no configuration mode");
}
FMI3_EXPORT fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) { (void)instance; return fmi3OK; }
