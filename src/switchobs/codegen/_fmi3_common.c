/* The FMI 3.0 functions every co-simulation wrapper of switchobs defines alike (the observer's and the quarter
 * car's), written once here and inserted into each wrapper by switchobs.codegen.fmi3_common.  They use the
 * wrapper's swobs_instance (fields mode, time, environment, log), SWOBS_INST, SWOBS_TOKEN, SWOBS_TERMINATED,
 * swobs_fail, swobs_reset, swobs_do_step, swobs_start (its own set-up of a new zeroed instance), and
 * SWOBS_ENDED(inst) / SWOBS_EARLY(inst): whether the last doStep ended the simulation / returned early. */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    (void)instance; (void)loggingOn; (void)nCategories; (void)categories;  /* every message is always logged */
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
    fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    if (logMessage != NULL) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                       "this FMU supports co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
    fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    swobs_instance *inst;
    (void)resourcePath; (void)visible; (void)loggingOn; (void)eventModeUsed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
    if (instantiationToken == NULL || strcmp(instantiationToken, SWOBS_TOKEN) != 0) {
        if (logMessage != NULL) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                           "the instantiation token does not match this FMU's " SWOBS_TOKEN);
        return NULL;
    }
    /* FMI 3.0 passes no memory callbacks: the instance is the one calloc of the FMU */
    inst = (swobs_instance *)calloc(1u, sizeof *inst);
    if (inst == NULL) return NULL;
    inst->environment = instanceEnvironment;
    inst->log = logMessage;
    return swobs_start(inst, instanceName, earlyReturnAllowed);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
    fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    return fmi3InstantiateModelExchange(instanceName, instantiationToken, resourcePath, visible, loggingOn,
                                        instanceEnvironment, logMessage);
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return instance == NULL ? fmi3Error : swobs_fail(SWOBS_INST, "fmi3EnterEventMode", "this FMU has no event mode");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    if (instance == NULL) return fmi3Error;
    SWOBS_INST->mode = SWOBS_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    if (instance == NULL) return fmi3Error;
    swobs_reset(SWOBS_INST);
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return instance == NULL ? fmi3Error : fmi3OK;  /* exitInitializationMode already entered step mode */
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
    fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
    fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
    fmi3Float64 *lastSuccessfulTime)
{
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance == NULL) return fmi3Error;
    status = swobs_do_step(SWOBS_INST, currentCommunicationPoint, communicationStepSize);
    if (eventHandlingNeeded != NULL) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation != NULL) *terminateSimulation = SWOBS_ENDED(SWOBS_INST) ? fmi3True : fmi3False;
    if (earlyReturn != NULL) *earlyReturn = SWOBS_EARLY(SWOBS_INST) ? fmi3True : fmi3False;
    if (lastSuccessfulTime != NULL) *lastSuccessfulTime = SWOBS_INST->time;
    return status;
}
