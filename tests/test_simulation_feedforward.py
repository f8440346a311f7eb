"""A time-varying input (a feedforward u(t), as an optimal gait's torque profile) reaches every
event function, not only the flow: a stance foot's normal force depends on the torque applied at
that instant, so the verification must check the constraint with u(t), not the step's constant."""

import numpy as np

import gaitopt
from gaitopt.simulation.phase import PhaseFunctions


def test_events_see_the_feedforward_input_at_their_time():
    model = gaitopt.model("compass_gait")
    phase = model.phases[0]
    assert phase.constraints, "the compass gait declares its stance contact"
    x = model.lift(model.section_vector({}))
    p = model.p
    funcs = PhaseFunctions(phase, np.zeros(1), p)
    k = len(phase.transitions)  # the first constraint's event index

    def feedforward(tau, step):
        return np.array([40.0 * np.sin(7.0 * tau)])  # N·m, any profile that varies

    funcs._drive = (feedforward, 0.0, 0)
    for t in (0.0, 0.1, 0.23):
        # Independent: the constraint function called directly with u(t) (exact: same function).
        expected = float(phase.constraints[0].function(x, feedforward(t, 0), p))
        assert funcs.signed_guard(k, x, t) == -expected  # constraints fire falling: direction −1
    # ... and the constant input is not what it sees: the torque changes the normal force.
    constant = float(phase.constraints[0].function(x, np.zeros(1), p))
    assert abs(funcs.signed_guard(k, x, 0.23) + constant) > 1e-6
