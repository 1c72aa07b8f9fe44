"""The input checks (rotrod_core.numerics.checks) behind every public call: ints beyond the
float range are a ValueError."""

import pytest

from rotrod_core import (
    Eq26Profile,
    RodParams,
    TableProfile,
    critical_speed,
    dynamic_frequencies,
    estimate_whirl,
    simulate,
)
from rotrod_core.live.stepper import RealTimeStepper
from rotrod_core.offline.simulate import time_grid


def test_regression_ints_beyond_the_float_range_are_a_value_error():
    # float(10**400) raises OverflowError, which the validators let through
    big = 10**400
    calls = (lambda: RodParams(mass=big), lambda: Eq26Profile(period=big),
             lambda: Eq26Profile().omega(big), lambda: Eq26Profile().omega([0.0, big]),
             lambda: TableProfile([0, big], [0, 1]), lambda: time_grid(big, 1e-3),
             lambda: dynamic_frequencies(RodParams(), big),
             lambda: critical_speed(RodParams(), big),
             lambda: RealTimeStepper(RodParams()).step_velocity(big),
             lambda: RealTimeStepper(RodParams(), initial={'u': big}),
             lambda: estimate_whirl([0, 1, big], [0, 0, 0], [0, 0, 0]),
             lambda: simulate(RodParams(), torque=big, t_end=0.01),
             lambda: simulate(RodParams(), torque=lambda t: big, t_end=0.01))
    for call in calls:
        with pytest.raises(ValueError):
            call()
