"""The planner's answers under several OpenBLAS kernels and thread counts, side by side.

    .venv/bin/python bench/bench_planner_kernels.py [--quick]

Plans the same requests (Table 1 and a steel rod, 0 -> 2 rad/s, 3 mm; robust 0.1;
robust 0.1 within 0.45 rad/s^2, config/planned.yaml's) in fresh processes with
OPENBLAS_CORETYPE = the machine's default, Haswell and Sandybridge (FMA and no FMA:
different rounding in every matrix product) and with 1 or 2 OpenBLAS threads, and
prints one markdown row per request and setting: the duration to 1e-6 s, the peak and
largest |w'| to 9 digits, and the planning time. ``--quick`` leaves out the last
request (a minute or more per setting). docs/planner.md#limits-and-doubts quotes it.
"""

import argparse
import json
import os
import subprocess
import sys

SETTINGS = (('default, 1 thread', {'OPENBLAS_NUM_THREADS': '1'}),
            ('default, 2 threads', {'OPENBLAS_NUM_THREADS': '2'}),
            ('Haswell, 1 thread', {'OPENBLAS_CORETYPE': 'Haswell', 'OPENBLAS_NUM_THREADS': '1'}),
            ('Sandybridge, 1 thread', {'OPENBLAS_CORETYPE': 'Sandybridge',
                                       'OPENBLAS_NUM_THREADS': '1'}))

PLANS = """
import json, sys, time
from rotrod_core import RodParams, plan_spin_up
requests = {'Table 1': (RodParams(), {}),
            'steel rod': (RodParams(rod_density=7850.0), {}),
            'robust 0.1, 1 um': (RodParams(), {'robust': 0.1, 'residual': 1e-6}),
            "robust 0.1, |w'| <= 0.45": (RodParams(), {'robust': 0.1,
                                                       'max_angular_acceleration': 0.45})}
out = {}
for name in sys.argv[1:]:
    params, kwargs = requests[name]
    t0 = time.perf_counter()
    plan = plan_spin_up(params, 2.0, **kwargs)
    out[name] = [plan.duration, plan.peak_deflection, plan.max_angular_acceleration,
                 time.perf_counter() - t0]
json.dump(out, sys.stdout)
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--quick', action='store_true', help="leave out the robust request "
                    "within 0.45 rad/s^2")
    args = ap.parse_args()
    names = ['Table 1', 'steel rod', 'robust 0.1, 1 um']
    if not args.quick:
        names.append("robust 0.1, |w'| <= 0.45")
    base = {k: v for k, v in os.environ.items() if not k.startswith('OPENBLAS')}
    base['ROTROD_PLAN_CACHE'] = 'off'   # plan_cache.ENV, .OFF: each kernel plans for itself
    print("| request (0 -> 2 rad/s, 3 mm) | OpenBLAS | duration [s] | peak [mm] "
          "| largest \\|w'\\| [rad/s^2] | planning time [s] |")
    print('|---|---|---|---|---|---|')
    results = {}
    for label, extra in SETTINGS:
        out = subprocess.run([sys.executable, '-c', PLANS, *names], env={**base, **extra},
                             capture_output=True, text=True, check=True).stdout
        results[label] = json.loads(out)
    for name in names:
        for label, _ in SETTINGS:
            T, peak, acc, seconds = results[label][name]
            cell = name.replace('|', '\\|')
            print(f'| {cell} | {label} | {T:.6f} | {peak * 1e3:.9f} | {acc:.9g} '
                  f'| {seconds:.1f} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
