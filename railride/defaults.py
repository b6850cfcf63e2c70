"""The defaults of a run, in one place: every module and the command line read them here."""

#: fixed step [s], RK4's: resolves the MR dampers' hysteresis (docs/model.md, Integration); the
#: exact discretisation of a linear vehicle steps once per output sample and reads it as the
#: spacing of its rail-input grid
DEFAULT_DT = 1e-4
#: rate of the stored time histories [Hz]
DEFAULT_OUTPUT_RATE = 1000.0
#: sample rate of the outer-loop controllers [Hz]
DEFAULT_CONTROL_RATE = 1000.0
#: the MR damper of a vehicle run when none is named
DEFAULT_DAMPER = "railway"
#: the vehicle's speed [m/s] (V, the paper's value)
DEFAULT_SPEED = 55.56
#: the length of a run [s] where its scenario gives none
DEFAULT_DURATION = 10.0
#: how a tuning study scores a run when no objective is named (`railride.studies.objectives.DEFAULT_OBJECTIVE`)
DEFAULT_OBJECTIVE_KIND = "minimax"
