"""rotrod_core: a tip mass on a flexible rod standing on a rotating disk (no ROS).

The rigid-flexible coupled model of Liu et al. (Appl. Math. Modell. 2014), with the
exact Lagrangian torque coupling, in SI units throughout. Public contract:
``RodParams``, ``Eq26Profile``, ``simulate``, ``dynamic_frequencies``,
``critical_speed``, ``estimate_whirl_frequencies`` and the other names below.

The names are imported on first use (PEP 562): a process that needs only part of the
package (a node importing ``rotrod_core.live``) does not pay for the rest (the planner's,
the identification's and the analyses' SciPy modules).
"""

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rotrod_core.analysis.critical import (
        critical_speed,
        critical_speed_for_profile,
        critical_speed_from,
    )
    from rotrod_core.analysis.modes import (
        CampbellDiagram,
        ModalAnalysis,
        Mode,
        campbell,
        dynamic_frequencies,
        modal_analysis,
        static_deflection,
    )
    from rotrod_core.command.planner import plan_spin_up, whirl_residual
    from rotrod_core.command.profiles import (
        ConstantProfile,
        Eq26Profile,
        Profile,
        RampProfile,
        SineSweepProfile,
        SpinUpProfile,
        StepProfile,
        TableProfile,
        make_profile,
    )
    from rotrod_core.estimation.identify import (
        NotIdentifiable,
        RigEstimate,
        RigIdentifier,
        identify_rig,
        rig_cramer_rao,
    )
    from rotrod_core.estimation.whirl import (
        Whirl,
        WhirlEstimate,
        WhirlEstimator,
        WhirlSettings,
        estimate_whirl,
        estimate_whirl_frequencies,
    )
    from rotrod_core.live.stepper import RealTimeStepper
    from rotrod_core.model.equations import State
    from rotrod_core.model.params import DEFAULT_HUB_INERTIA, RodParams, disk_inertia
    from rotrod_core.numerics.checks import NonFiniteStateError
    from rotrod_core.offline.batch import BatchResult, simulate_batch
    from rotrod_core.offline.result import SimulationResult
    from rotrod_core.offline.simulate import simulate

_SOURCES = {
    'rotrod_core.analysis.critical': (
        'critical_speed', 'critical_speed_for_profile', 'critical_speed_from'),
    'rotrod_core.analysis.modes': (
        'CampbellDiagram', 'ModalAnalysis', 'Mode', 'campbell', 'dynamic_frequencies',
        'modal_analysis', 'static_deflection'),
    'rotrod_core.command.planner': ('plan_spin_up', 'whirl_residual'),
    'rotrod_core.command.profiles': (
        'ConstantProfile', 'Eq26Profile', 'Profile', 'RampProfile', 'SineSweepProfile',
        'SpinUpProfile', 'StepProfile', 'TableProfile', 'make_profile'),
    'rotrod_core.estimation.identify': (
        'NotIdentifiable', 'RigEstimate', 'RigIdentifier', 'identify_rig', 'rig_cramer_rao'),
    'rotrod_core.estimation.whirl': (
        'Whirl', 'WhirlEstimate', 'WhirlEstimator', 'WhirlSettings', 'estimate_whirl',
        'estimate_whirl_frequencies'),
    'rotrod_core.live.stepper': ('RealTimeStepper',),
    'rotrod_core.model.equations': ('State',),
    'rotrod_core.model.params': ('DEFAULT_HUB_INERTIA', 'RodParams', 'disk_inertia'),
    'rotrod_core.numerics.checks': ('NonFiniteStateError',),
    'rotrod_core.offline.batch': ('BatchResult', 'simulate_batch'),
    'rotrod_core.offline.result': ('SimulationResult',),
    'rotrod_core.offline.simulate': ('simulate',),
}
"""The module that defines each public name."""
_MODULE_OF = {name: module for module, names in _SOURCES.items() for name in names}


def __getattr__(name: str):
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted({*globals(), *_MODULE_OF})


__all__ = [
    'BatchResult', 'CampbellDiagram', 'ConstantProfile', 'DEFAULT_HUB_INERTIA',
    'Eq26Profile', 'ModalAnalysis', 'Mode', 'NonFiniteStateError', 'NotIdentifiable',
    'Profile', 'RampProfile', 'RealTimeStepper', 'RigEstimate', 'RigIdentifier',
    'RodParams', 'SimulationResult', 'SineSweepProfile', 'State',
    'StepProfile',
    'TableProfile', 'Whirl', 'WhirlEstimate', 'WhirlEstimator', 'WhirlSettings', 'campbell',
    'critical_speed', 'critical_speed_for_profile', 'critical_speed_from', 'disk_inertia',
    'dynamic_frequencies', 'estimate_whirl', 'estimate_whirl_frequencies', 'identify_rig',
    'make_profile', 'modal_analysis', 'plan_spin_up', 'rig_cramer_rao',
    'simulate', 'simulate_batch', 'SpinUpProfile', 'static_deflection', 'whirl_residual',
]
