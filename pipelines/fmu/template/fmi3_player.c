/* FMI 3.0 co-simulation wrapper around the history player (player.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "player.h"

typedef enum { STATE_INSTANTIATED, STATE_INITIALIZATION, STATE_STEPPING, STATE_TERMINATED } State;

typedef struct {
    Player player;
    State state;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message;
} Instance;

static void log_error(fmi3LogMessageCallback log_message, fmi3InstanceEnvironment environment, const char *message) {
    if (log_message) {
        log_message(environment, fmi3Error, "logStatusError", message);
    }
}

static fmi3Status unsupported(fmi3Instance c, const char *function) {
    Instance *instance = (Instance *)c;
    char message[128];
    snprintf(message, sizeof(message), "%s is not supported by this history player", function);
    if (instance) {
        log_error(instance->log_message, instance->environment, message);
    }
    return fmi3Error;
}

static fmi3Status bad_reference(fmi3Instance c, fmi3ValueReference vr, const char *what) {
    Instance *instance = (Instance *)c;
    char message[128];
    snprintf(message, sizeof(message), "value reference %u is not a %s of this FMU", (unsigned)vr, what);
    log_error(instance->log_message, instance->environment, message);
    return fmi3Error;
}

static int is_output(const Instance *instance, fmi3ValueReference vr) {
    return vr >= PLAYER_VR_FIRST_OUTPUT && vr - PLAYER_VR_FIRST_OUTPUT < instance->player.n_signals;
}

static fmi3Status check_parameters_settable(Instance *instance) {
    if (instance->state != STATE_INSTANTIATED && instance->state != STATE_INITIALIZATION) {
        log_error(instance->log_message, instance->environment,
                  "time_offset, period and periodic are fixed parameters: set them before initialization ends");
        return fmi3Error;
    }
    return fmi3OK;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)instance;
    (void)loggingOn;
    (void)nCategories;
    (void)categories;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    log_error(logMessage, instanceEnvironment, "only co-simulation is supported");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    Instance *instance;
    char message[4352];
    (void)instanceName;
    (void)visible;
    (void)loggingOn;
    (void)eventModeUsed;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;

    instance = (Instance *)calloc(1, sizeof(Instance));
    if (!instance) {
        log_error(logMessage, instanceEnvironment, "out of memory");
        return NULL;
    }
    if (player_load(&instance->player, resourcePath, instantiationToken, message, sizeof(message)) != 0) {
        log_error(logMessage, instanceEnvironment, message);
        free(instance);
        return NULL;
    }
    instance->environment = instanceEnvironment;
    instance->log_message = logMessage;
    instance->state = STATE_INSTANTIATED;
    instance->player.current_time = instance->player.time[0];
    return instance;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    log_error(logMessage, instanceEnvironment, "only co-simulation is supported");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c) {
    Instance *instance = (Instance *)c;
    if (!instance) {
        return;
    }
    player_free(&instance->player);
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Instance *instance = (Instance *)c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    instance->player.current_time = startTime;
    instance->player.outputs_valid = 0;
    instance->state = STATE_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    Instance *instance = (Instance *)c;
    char message[256];
    if (player_check_parameters(&instance->player, message, sizeof(message)) != 0) {
        log_error(instance->log_message, instance->environment, message);
        return fmi3Error;
    }
    instance->state = STATE_STEPPING;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) {
    (void)c;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance c) {
    ((Instance *)c)->state = STATE_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance c) {
    Instance *instance = (Instance *)c;
    Player *player = &instance->player;
    player->time_offset = 0.0;
    player->period = player->time[player->n_samples - 1] - player->time[0];
    player->periodic = 0;
    player->current_time = player->time[0];
    player->outputs_valid = 0;
    instance->state = STATE_INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    Instance *instance = (Instance *)c;
    const double *outputs = player_outputs(&instance->player);
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; i++) {
        fmi3ValueReference vr = valueReferences[i];
        if (vr == PLAYER_VR_TIME) {
            values[i] = instance->player.current_time;
        } else if (vr == PLAYER_VR_TIME_OFFSET) {
            values[i] = instance->player.time_offset;
        } else if (vr == PLAYER_VR_PERIOD) {
            values[i] = instance->player.period;
        } else if (is_output(instance, vr)) {
            values[i] = outputs[vr - PLAYER_VR_FIRST_OUTPUT];
        } else {
            return bad_reference(c, vr, "Float64 variable");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    Instance *instance = (Instance *)c;
    size_t i;
    (void)nValues;
    if (nValueReferences > 0 && check_parameters_settable(instance) != fmi3OK) {
        return fmi3Error;
    }
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] == PLAYER_VR_TIME_OFFSET) {
            instance->player.time_offset = values[i];
        } else if (valueReferences[i] == PLAYER_VR_PERIOD) {
            instance->player.period = values[i];
        } else {
            return bad_reference(c, valueReferences[i], "settable Float64 parameter");
        }
    }
    instance->player.outputs_valid = 0;
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Boolean values[], size_t nValues) {
    Instance *instance = (Instance *)c;
    size_t i;
    (void)nValues;
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] != PLAYER_VR_PERIODIC) {
            return bad_reference(c, valueReferences[i], "Boolean variable");
        }
        values[i] = instance->player.periodic ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Boolean values[], size_t nValues) {
    Instance *instance = (Instance *)c;
    size_t i;
    (void)nValues;
    if (nValueReferences > 0 && check_parameters_settable(instance) != fmi3OK) {
        return fmi3Error;
    }
    for (i = 0; i < nValueReferences; i++) {
        if (valueReferences[i] != PLAYER_VR_PERIODIC) {
            return bad_reference(c, valueReferences[i], "settable Boolean parameter");
        }
        instance->player.periodic = values[i] ? 1 : 0;
    }
    instance->player.outputs_valid = 0;
    return fmi3OK;
}

/* The player has no variables of the remaining types: any value reference is wrong. */
#define NO_VARIABLES_GETTER(NAME, TYPE)                                                                   \
    fmi3Status NAME(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                    TYPE values[], size_t nValues) {                                                      \
        (void)values;                                                                                     \
        (void)nValues;                                                                                    \
        return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], #TYPE " variable");  \
    }

#define NO_VARIABLES_SETTER(NAME, TYPE)                                                                   \
    fmi3Status NAME(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                    const TYPE values[], size_t nValues) {                                                \
        (void)values;                                                                                     \
        (void)nValues;                                                                                    \
        return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], #TYPE " variable");  \
    }

NO_VARIABLES_GETTER(fmi3GetFloat32, fmi3Float32)
NO_VARIABLES_GETTER(fmi3GetInt8, fmi3Int8)
NO_VARIABLES_GETTER(fmi3GetUInt8, fmi3UInt8)
NO_VARIABLES_GETTER(fmi3GetInt16, fmi3Int16)
NO_VARIABLES_GETTER(fmi3GetUInt16, fmi3UInt16)
NO_VARIABLES_GETTER(fmi3GetInt32, fmi3Int32)
NO_VARIABLES_GETTER(fmi3GetUInt32, fmi3UInt32)
NO_VARIABLES_GETTER(fmi3GetInt64, fmi3Int64)
NO_VARIABLES_GETTER(fmi3GetUInt64, fmi3UInt64)
NO_VARIABLES_GETTER(fmi3GetString, fmi3String)
NO_VARIABLES_SETTER(fmi3SetFloat32, fmi3Float32)
NO_VARIABLES_SETTER(fmi3SetInt8, fmi3Int8)
NO_VARIABLES_SETTER(fmi3SetUInt8, fmi3UInt8)
NO_VARIABLES_SETTER(fmi3SetInt16, fmi3Int16)
NO_VARIABLES_SETTER(fmi3SetUInt16, fmi3UInt16)
NO_VARIABLES_SETTER(fmi3SetInt32, fmi3Int32)
NO_VARIABLES_SETTER(fmi3SetUInt32, fmi3UInt32)
NO_VARIABLES_SETTER(fmi3SetInt64, fmi3Int64)
NO_VARIABLES_SETTER(fmi3SetUInt64, fmi3UInt64)
NO_VARIABLES_SETTER(fmi3SetString, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], "Binary variable");
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], "Binary variable");
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    (void)values;
    return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], "Clock");
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    (void)values;
    return nValueReferences == 0 ? fmi3OK : bad_reference(c, valueReferences[0], "Clock");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference;
    (void)nDependencies;
    return unsupported(c, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return unsupported(c, "fmi3GetVariableDependencies");
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *FMUState) {
    (void)FMUState;
    return unsupported(c, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState) {
    (void)FMUState;
    return unsupported(c, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *FMUState) {
    (void)FMUState;
    return unsupported(c, "fmi3FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState;
    (void)size;
    return unsupported(c, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    (void)FMUState;
    (void)serializedState;
    (void)size;
    return unsupported(c, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    (void)serializedState;
    (void)size;
    (void)FMUState;
    return unsupported(c, "fmi3DeserializeFMUState");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(c, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(c, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3EnterConfigurationMode"); }

fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3ExitConfigurationMode"); }

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    (void)qualifiers;
    return unsupported(c, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return unsupported(c, "fmi3GetIntervalFraction");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               fmi3Float64 shifts[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(c, "fmi3GetShiftDecimal");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(c, "fmi3GetShiftFraction");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    return unsupported(c, "fmi3SetIntervalDecimal");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(c, "fmi3SetIntervalFraction");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                               const fmi3Float64 shifts[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(c, "fmi3SetShiftDecimal");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(c, "fmi3SetShiftFraction");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) {
    (void)c;
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    (void)c;
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { return unsupported(c, "fmi3EnterContinuousTimeMode"); }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(c, "fmi3CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) {
    (void)time;
    return unsupported(c, "fmi3SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(c, "fmi3SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 derivatives[], size_t nContinuousStates) {
    (void)derivatives;
    (void)nContinuousStates;
    return unsupported(c, "fmi3GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators;
    (void)nEventIndicators;
    return unsupported(c, "fmi3GetEventIndicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(c, "fmi3GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[], size_t nContinuousStates) {
    (void)nominals;
    (void)nContinuousStates;
    return unsupported(c, "fmi3GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *nEventIndicators) {
    (void)c;
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *nContinuousStates) {
    (void)c;
    *nContinuousStates = 0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance c) {
    ((Instance *)c)->state = STATE_STEPPING;
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)valueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return nValueReferences == 0 ? fmi3OK : unsupported(c, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    Instance *instance = (Instance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance->state != STATE_STEPPING) {
        log_error(instance->log_message, instance->environment, "fmi3DoStep called outside step mode");
        return fmi3Error;
    }
    instance->player.current_time = currentCommunicationPoint + communicationStepSize;
    instance->player.outputs_valid = 0;
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = instance->player.current_time;
    return fmi3OK;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference;
    (void)activationTime;
    return unsupported(c, "fmi3ActivateModelPartition");
}
