"""Step-to-step control: one deadbeat decision of the SLIP's touchdown angle timed in Python, as
generated C (in a C driver and through ``casadi.external``) and by simulation with ``brentq``, as
the textbook notebook does (see :mod:`bench.run`); and its lines of the printed report."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
from typing import Any

import numpy as np

from .common import _median, _sci

__all__: list[str] = []

_C_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "deadbeat_policy.h"
static double now(void) {
  struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec;
}
static int by_value(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b; return (x > y) - (x < y);
}
/* argv: N_P parameters, the target, then the states (one section coordinate each). */
int main(int argc, char** argv) {
  casadi_int n_arg, n_res, n_iw, n_w;
  deadbeat_policy_work(&n_arg, &n_res, &n_iw, &n_w);
  const casadi_real** arg = malloc(sizeof(*arg) * n_arg);
  casadi_real** res = malloc(sizeof(*res) * n_res);
  casadi_int* iw = malloc(sizeof(*iw) * (n_iw + 1));
  casadi_real* w = malloc(sizeof(*w) * (n_w + 1));
  double p[N_P], target[1], s[1], u[1], T[N_T], r[1];
  for (int i = 0; i < N_P; i++) p[i] = atof(argv[1 + i]);
  target[0] = atof(argv[1 + N_P]);
  int n = argc - 2 - N_P, repeats = REPEATS;
  double* dt = malloc(sizeof(double) * n * repeats);
  arg[0] = s; arg[1] = target; arg[2] = p; res[0] = u; res[1] = T; res[2] = r;
  printf("{\"u\": [");
  for (int k = 0; k < n; k++) {
    s[0] = atof(argv[2 + N_P + k]);
    for (int j = 0; j < repeats; j++) {
      double t0 = now();
      deadbeat_policy(arg, res, iw, w, 0);
      dt[k * repeats + j] = now() - t0;
    }
    printf("%s%.17g", k ? ", " : "", u[0]);
  }
  qsort(dt, (size_t)(n * repeats), sizeof(double), by_value);
  printf("], \"median_s\": %.9g, \"min_s\": %.9g, \"calls\": %d}\n",
         dt[n * repeats / 2], dt[0], n * repeats);
  return 0;
}
"""


def _deadbeat_bench(decisions: int) -> dict[str, Any]:
    """Time one deadbeat decision of the SLIP (see :mod:`bench.run`)."""
    import casadi as ca
    from scipy.optimize import brentq

    import gaitopt
    from gaitopt.control import deadbeat
    from gaitopt.returnmap import return_map

    slip = gaitopt.model("slip")
    controller = deadbeat(slip)
    solver = controller.deadbeat_solver
    z_star = float(controller.target[0])
    rng = np.random.default_rng(0)
    # Apex heights from 5 mm below to 3 cm above the gait (inside the feasible range, above the
    # touchdown height): the disturbances a running controller sees.
    states = z_star + rng.uniform(-0.005, 0.03, decisions)
    out: dict[str, Any] = {
        "model": "slip",
        "params": slip.params,
        "target_z": z_star,
        "states": {"low": float(states.min()), "high": float(states.max()), "count": decisions},
    }

    controller.decide([states[0]])  # warm-up (builds the rootfinder)
    times, inputs = [], []
    for z in states:
        t0 = time.perf_counter()
        decision = controller.decide([z])
        times.append(time.perf_counter() - t0)
        inputs.append(float(decision.input[0]))
    out["python"] = {
        "method": "StepController.decide: CasADi newton rootfinder on the multiple-shooting "
        "equations (+ validity checks)",
        "median_s": _median(times),
        "min_s": float(min(times)),
    }

    t0 = time.perf_counter()
    generated = solver.codegen()
    build_s = time.perf_counter() - t0
    policy = generated.function
    external = []
    c_inputs = []
    for z in states:
        t0 = time.perf_counter()
        u, _, _ = policy([z], [z_star], slip.p)
        external.append(time.perf_counter() - t0)
        c_inputs.append(float(u))
    folder = generated.library.parent
    driver = folder / "driver"
    if not driver.exists():
        n_t = int(policy.size1_out(1))
        source = folder / "driver.c"
        source.write_text(_C_DRIVER)
        compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc") or "cc"
        subprocess.run(
            [compiler, "-O2", f"-DN_P={slip.p.size}", f"-DN_T={n_t}", "-DREPEATS=5",
             f"-I{folder}", str(source), str(generated.library), f"-Wl,-rpath,{folder}",
             "-o", str(driver), "-lm"],
            check=True, capture_output=True, text=True,
        )  # fmt: skip
    argv = [str(driver), *(repr(float(v)) for v in slip.p), repr(z_star)]
    proc = subprocess.run(
        argv + [repr(float(z)) for z in states], capture_output=True, text=True, check=True
    )
    in_c = json.loads(proc.stdout)
    agreement = float(np.max(np.abs(np.array(in_c["u"]) - np.array(inputs))))
    out["generated_c"] = {
        "method": "Deadbeat.codegen: CasADi Function.generate of a single-shooting fast_newton "
        "policy, compiled -O3 -shared; timed by a C driver (clock_gettime per call)",
        "source": str(generated.source),
        "source_bytes": generated.source.stat().st_size,
        "generate_and_compile_s": build_s,
        "median_s": in_c["median_s"],
        "min_s": in_c["min_s"],
        "calls": in_c["calls"],
        "median_s_via_casadi_external": _median(external),
        "max_abs_difference_vs_python_rad": agreement,
        "max_abs_difference_external_vs_python_rad": float(
            np.max(np.abs(np.array(c_inputs) - np.array(inputs)))
        ),
        "casadi": ca.__version__,
    }

    theta = float(controller.nominal_input[0])
    map_times = []
    for z in states[: max(10, decisions // 10)]:
        t0 = time.perf_counter()
        return_map(slip, float(z), inputs=[theta])
        map_times.append(time.perf_counter() - t0)
    brent_times, brent_errors, evaluations = [], [], []
    for z, u_ref in list(zip(states, inputs, strict=True))[: max(5, decisions // 20)]:
        count = [0]

        def defect(th: float, z: float = float(z), count: list = count) -> float:
            count[0] += 1
            return float(return_map(slip, z, inputs=[th])[0]) - z_star

        t0 = time.perf_counter()
        width = 0.04  # bracket around the answer, shrunk where the map is undefined at an end
        while not np.isfinite(defect(u_ref - width) * defect(u_ref + width)):
            width /= 2
        root = brentq(defect, u_ref - width, u_ref + width, xtol=1e-12)
        brent_times.append(time.perf_counter() - t0)
        brent_errors.append(abs(root - u_ref))
        evaluations.append(count[0])
    out["simulation"] = {
        "method": "apex map by event-located SciPy simulation (DOP853, rtol 1e-11), as in the "
        "textbook notebook; decision: brentq on it (bracket ±0.04 rad about the answer, halved "
        "while the map is undefined at an end; xtol 1e-12)",
        "map_evaluation_median_s": _median(map_times),
        "decision_median_s": _median(brent_times),
        "decision_map_evaluations_median": _median(evaluations),
        "decision_max_abs_difference_vs_python_rad": float(max(brent_errors)),
    }
    out["goal_decision_at_most_50us"] = bool(in_c["median_s"] <= 50e-6)
    return out


def _control_lines(c: dict[str, Any]) -> list[str]:
    """The control section of the printed report."""
    if "skipped" in c:
        return ["", f"Deadbeat decision (slip): skipped — {c['skipped']}"]
    py, gen, sim = c["python"], c["generated_c"], c["simulation"]

    def us(s: float) -> str:
        return f"{1e6 * s:.3g} µs" if s < 1e-3 else f"{1e3 * s:.3g} ms"

    verdict = "met" if c["goal_decision_at_most_50us"] else "NOT met"
    return [
        "",
        f"Deadbeat decision, slip touchdown angle (apex z in [{c['states']['low']:.4f}, "
        f"{c['states']['high']:.4f}] m → z* = {c['target_z']:.6f} m, {c['states']['count']} "
        f"apex heights):",
        f"  Python (CasADi rootfinder, multiple shooting)   median {us(py['median_s'])}",
        f"  generated C (fast_newton, in a C driver)        median {us(gen['median_s'])} "
        f"(via casadi.external from Python {us(gen['median_s_via_casadi_external'])}); "
        f"|Δθ| vs Python {_sci(gen['max_abs_difference_vs_python_rad'])} rad; generate + "
        f"compile {gen['generate_and_compile_s']:.1f} s (cached for later runs)",
        f"  apex map by simulation (SciPy, one evaluation)  median "
        f"{us(sim['map_evaluation_median_s'])}; deadbeat by brentq on it "
        f"{us(sim['decision_median_s'])} ({sim['decision_map_evaluations_median']:.0f} "
        f"evaluations)",
        f"  goal: a decision ≤ 50 µs from the generated code — {verdict}",
    ]
