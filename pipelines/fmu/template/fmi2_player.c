/* FMI 2.0 co-simulation wrapper around the history player (player.h). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "player.h"

typedef enum { STATE_INSTANTIATED, STATE_INITIALIZATION, STATE_STEPPING, STATE_TERMINATED } State;

typedef struct {
    Player player;
    State state;
    char *instance_name;
    fmi2CallbackFunctions callbacks;
    fmi2Boolean logging_on;
} Instance;

static void log_error(const fmi2CallbackFunctions *callbacks, fmi2String instance_name, const char *message) {
    if (callbacks && callbacks->logger) {
        callbacks->logger(callbacks->componentEnvironment, instance_name, fmi2Error, "logStatusError", "%s", message);
    }
}

static fmi2Status unsupported(fmi2Component c, const char *function) {
    Instance *instance = (Instance *)c;
    char message[128];
    snprintf(message, sizeof(message), "%s is not supported by this history player", function);
    if (instance) {
        log_error(&instance->callbacks, instance->instance_name, message);
    }
    return fmi2Error;
}

static fmi2Status bad_reference(Instance *instance, fmi2ValueReference vr, const char *what) {
    char message[128];
    snprintf(message, sizeof(message), "value reference %u is not a %s of this FMU", (unsigned)vr, what);
    log_error(&instance->callbacks, instance->instance_name, message);
    return fmi2Error;
}

static int is_output(const Instance *instance, fmi2ValueReference vr) {
    return vr >= PLAYER_VR_FIRST_OUTPUT && vr - PLAYER_VR_FIRST_OUTPUT < instance->player.n_signals;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    ((Instance *)c)->logging_on = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    Instance *instance;
    char resource_dir[4096];
    char message[4352];
    (void)visible;

    if (fmuType != fmi2CoSimulation) {
        log_error(functions, instanceName, "only co-simulation is supported");
        return NULL;
    }
    if (player_uri_to_path(fmuResourceLocation, resource_dir, sizeof(resource_dir)) != 0) {
        log_error(functions, instanceName, "missing or too long fmuResourceLocation");
        return NULL;
    }
    instance = (Instance *)calloc(1, sizeof(Instance));
    if (!instance) {
        log_error(functions, instanceName, "out of memory");
        return NULL;
    }
    if (player_load(&instance->player, resource_dir, fmuGUID, message, sizeof(message)) != 0) {
        log_error(functions, instanceName, message);
        free(instance);
        return NULL;
    }
    instance->instance_name = (char *)malloc(strlen(instanceName ? instanceName : "") + 1);
    if (!instance->instance_name) {
        player_free(&instance->player);
        free(instance);
        return NULL;
    }
    strcpy(instance->instance_name, instanceName ? instanceName : "");
    if (functions) {
        instance->callbacks = *functions;
    }
    instance->logging_on = loggingOn;
    instance->state = STATE_INSTANTIATED;
    instance->player.current_time = instance->player.time[0];
    return instance;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!instance) {
        return;
    }
    player_free(&instance->player);
    free(instance->instance_name);
    free(instance);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *instance = (Instance *)c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    instance->player.current_time = startTime;
    instance->player.outputs_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ((Instance *)c)->state = STATE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *instance = (Instance *)c;
    char message[256];
    if (player_check_parameters(&instance->player, message, sizeof(message)) != 0) {
        log_error(&instance->callbacks, instance->instance_name, message);
        return fmi2Error;
    }
    instance->state = STATE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ((Instance *)c)->state = STATE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *instance = (Instance *)c;
    Player *player = &instance->player;
    player->time_offset = 0.0;
    player->period = player->time[player->n_samples - 1] - player->time[0];
    player->periodic = 0;
    player->current_time = player->time[0];
    player->outputs_valid = 0;
    instance->state = STATE_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Instance *instance = (Instance *)c;
    const double *outputs = player_outputs(&instance->player);
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] == PLAYER_VR_TIME_OFFSET) {
            value[i] = instance->player.time_offset;
        } else if (vr[i] == PLAYER_VR_PERIOD) {
            value[i] = instance->player.period;
        } else if (is_output(instance, vr[i])) {
            value[i] = outputs[vr[i] - PLAYER_VR_FIRST_OUTPUT];
        } else {
            return bad_reference(instance, vr[i], "Real variable");
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : bad_reference((Instance *)c, vr[0], "Integer variable");
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    Instance *instance = (Instance *)c;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != PLAYER_VR_PERIODIC) {
            return bad_reference(instance, vr[i], "Boolean variable");
        }
        value[i] = instance->player.periodic ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : bad_reference((Instance *)c, vr[0], "String variable");
}

static fmi2Status check_parameters_settable(Instance *instance) {
    if (instance->state != STATE_INSTANTIATED && instance->state != STATE_INITIALIZATION) {
        log_error(&instance->callbacks, instance->instance_name,
                  "time_offset, period and periodic are fixed parameters: set them before initialization ends");
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Instance *instance = (Instance *)c;
    size_t i;
    if (nvr > 0 && check_parameters_settable(instance) != fmi2OK) {
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        if (vr[i] == PLAYER_VR_TIME_OFFSET) {
            instance->player.time_offset = value[i];
        } else if (vr[i] == PLAYER_VR_PERIOD) {
            instance->player.period = value[i];
        } else {
            return bad_reference(instance, vr[i], "settable Real parameter");
        }
    }
    instance->player.outputs_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : bad_reference((Instance *)c, vr[0], "settable Integer parameter");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    Instance *instance = (Instance *)c;
    size_t i;
    if (nvr > 0 && check_parameters_settable(instance) != fmi2OK) {
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        if (vr[i] != PLAYER_VR_PERIODIC) {
            return bad_reference(instance, vr[i], "settable Boolean parameter");
        }
        instance->player.periodic = value[i] ? 1 : 0;
    }
    instance->player.outputs_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : bad_reference((Instance *)c, vr[0], "settable String parameter");
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    (void)FMUstate;
    return unsupported(c, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    (void)FMUstate;
    return unsupported(c, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    (void)FMUstate;
    return unsupported(c, "fmi2FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    (void)FMUstate;
    (void)size;
    return unsupported(c, "fmi2SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    (void)FMUstate;
    (void)serializedState;
    (void)size;
    return unsupported(c, "fmi2SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    (void)serializedState;
    (void)size;
    (void)FMUstate;
    return unsupported(c, "fmi2DeSerializeFMUstate");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { return unsupported(c, "fmi2EnterEventMode"); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *fmi2eventInfo) {
    (void)fmi2eventInfo;
    return unsupported(c, "fmi2NewDiscreteStates");
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return unsupported(c, "fmi2EnterContinuousTimeMode"); }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(c, "fmi2CompletedIntegratorStep");
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    return unsupported(c, "fmi2SetTime");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return unsupported(c, "fmi2SetContinuousStates");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    (void)derivatives;
    (void)nx;
    return unsupported(c, "fmi2GetDerivatives");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    (void)ni;
    return unsupported(c, "fmi2GetEventIndicators");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return unsupported(c, "fmi2GetContinuousStates");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal;
    (void)nx;
    return unsupported(c, "fmi2GetNominalsOfContinuousStates");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetRealInputDerivatives (the FMU has no inputs)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *instance = (Instance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance->state != STATE_STEPPING) {
        log_error(&instance->callbacks, instance->instance_name, "fmi2DoStep called before initialization ended");
        return fmi2Error;
    }
    instance->player.current_time = currentCommunicationPoint + communicationStepSize;
    instance->player.outputs_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s == fmi2LastSuccessfulTime) {
        *value = ((Instance *)c)->player.current_time;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetRealStatus for this status kind");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
