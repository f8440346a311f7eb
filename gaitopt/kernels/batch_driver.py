"""The C source of the compiled batch simulation (:mod:`gaitopt.simulation.batch_compiled`).

``gaitopt_batch`` runs many starts of one model to their end in one call: per start the loop of
:func:`gaitopt.simulate` (the unilateral constraints checked where a phase begins, a state
resting on a guard as standing, each phase one arc of :mod:`gaitopt.kernels.arc_driver`'s
``gaitopt_arc`` — SciPy's DOP853 control, strict directional crossings, Brent's root on the
dense output, admissibility —, the reset into the next phase, the returns to the section and an
accumulation of impacts, :func:`gaitopt.simulation.zeno.accumulation`), each start with its own
step sizes and event state.  The model enters only through the addresses of its compiled
functions (the arc library's guards, rates, resets and constraint checks, the verification's
DOP853 steps), so this library is model-independent: :data:`SOURCE` is the arc driver with this
loop after it, compiled once (:func:`batch_library`; cached like every kernel,
:mod:`gaitopt.kernels.cache`) and loaded with ``ctypes``.
"""

from __future__ import annotations

import ctypes
import subprocess
import sys
from functools import lru_cache

from .arc_driver import DRIVER
from .cache import _compile, _key, cache_dir, compiler
from .lane_driver import LANES_SOURCE

__all__ = ["BATCH", "SOURCE", "STATUS_CODES", "batch_library", "lanes_library"]

#: The status codes ``gaitopt_batch`` writes, in order (``"overflow"``: the start's events did not
#: fit its event buffer; the caller runs it again with a larger one).
STATUS_CODES = ("running", "completed", "fell", "standing", "timeout", "failed", "invalid start",
                "overflow")  # fmt: skip

_PRELUDE = r"""
/* gaitopt batch driver: the types CasADi's generated code uses (its defaults) */
#define casadi_real double
#define casadi_int long long int
#define CASADI_SYMBOL_EXPORT
"""

BATCH = r"""
/* ---- gaitopt batch driver (gaitopt/kernels/batch_driver.py) ------------------------------ */
#define GAITOPT_ZENO_WINDOW 5   /* simulation/zeno.py: _ZENO_WINDOW */
#define GAITOPT_ZENO_SPREAD 0.1 /* simulation/zeno.py: _ZENO_SPREAD */
#define GAITOPT_ZENO_KEEP (2 * (GAITOPT_ZENO_WINDOW + 1) + 1)
#define GAITOPT_RATE 1e-9       /* phase.py: _CONSTRAINT_RATE */
#define GAITOPT_CAP 64          /* steps per gaitopt_arc call */
enum { B_RUNNING, B_COMPLETED, B_FELL, B_STANDING, B_TIMEOUT, B_FAILED, B_INVALID, B_OVERFLOW };

/* zeno.py: accumulation.  times: the last `count` reset times (at most GAITOPT_ZENO_KEEP),
   oldest first.  1 and the accumulation time in *when, or 0. */
static int gaitopt_zeno(const double* times, int count, double* when) {
  int lag, i;
  for (lag = 1; lag <= 2; lag++) {
    int needed = lag * (GAITOPT_ZENO_WINDOW + 1) + 1, positive = 1, near = 1;
    double t[GAITOPT_ZENO_WINDOW + 2], d[GAITOPT_ZENO_WINDOW + 1], r[GAITOPT_ZENO_WINDOW];
    double sum, mean;
    if (count < needed) return 0;
    /* times[-needed:][::-1][::lag][::-1] */
    for (i = 0; i < GAITOPT_ZENO_WINDOW + 2; i++)
      t[GAITOPT_ZENO_WINDOW + 1 - i] = times[count - 1 - lag * i];
    for (i = 0; i < GAITOPT_ZENO_WINDOW + 1; i++) {
      d[i] = t[i + 1] - t[i];
      positive = positive && d[i] > 0;
    }
    if (!positive) continue;
    for (i = 0; i < GAITOPT_ZENO_WINDOW; i++) r[i] = d[i + 1] / d[i];
    /* np.mean of 5 values: the first plus the pairwise sum (a plain loop below 8) of the rest */
    sum = 0.0;
    for (i = 1; i < GAITOPT_ZENO_WINDOW; i++) sum += r[i];
    mean = (r[0] + sum) / GAITOPT_ZENO_WINDOW;
    for (i = 0; i < GAITOPT_ZENO_WINDOW; i++)
      near = near && fabs(r[i] - mean) <= GAITOPT_ZENO_SPREAD * (1.0 - mean);
    if (mean < 1.0 && near) {
      *when = t[GAITOPT_ZENO_WINDOW + 1] + d[GAITOPT_ZENO_WINDOW] * mean / (1.0 - mean);
      return 1;
    }
  }
  return 0;
}

/* f(x, u, p) -> (out0, out1) through an opened call */
static int gaitopt_xup2(gaitopt_call* c, const double* x, const double* u, const double* p,
                        double* out0, double* out1) {
  c->arg[0] = x; c->arg[1] = u; c->arg[2] = p; c->res[0] = out0; c->res[1] = out1;
  return c->f(c->arg, c->res, c->iw, c->w, 0);
}

/*
  Many starts, each simulated to its end as gaitopt.simulate does (module docstring).
  dims: N, phases, E (events per phase, the stride of the per-event arrays), steps, n_u,
    u_stride (0: one input for all starts, else n_u), nmax (the largest phase's states),
    cap (events kept per start; 0: none), p_stride (0: one parameter vector for all starts,
    else n_p: start s reads p + s * p_stride).
  phase_dims (phases x 4): n, m (events), n_tr (transitions), n_c (constraints).
  trans (phases x E x 3): target, terminal, closes the cycle (per transition).
  flags (phases x E x 2): a constraint's at_start (index j < n_c), an event's at_end (index k < m).
  dirs (phases x E): the events' directions.
  fns (phases x 10): gaitopt_arc's table of each phase (step, events, admissible, flow,
    excursion; function and work each).  resets (phases x E x 2), starts (phases x 2): the
    resets' and the constraint checks' (function, work), 0 where none.
  u, p (per start by u_stride, p_stride), opts (rtol, atol, max_phase_time), x0 (N x n of
    phase 0), status (in: B_RUNNING or B_INVALID per start; out: the end).
  Out per start: last (phase * E + event of the terminal event, -1), returns, t_end, phase_end,
    acc (accumulation time, NaN), sec_t (N x (steps+1)), sec_x (N x (steps+1) x n0), and with
    cap > 0: counts, ev_t (N x cap), ev_code (N x cap: phase * E + event), ev_before,
    ev_after (N x cap x nmax; after NaN where none).
  Returns 0, or -1 where a function failed or memory ran out.
*/
CASADI_SYMBOL_EXPORT int gaitopt_batch(
    const int* dims, const int* phase_dims, const int* trans, const int* flags,
    const double* dirs, void** fns, void** resets, void** starts, const double* u,
    const double* p_all, const double* opts, const double* x0, int* status, int* last,
    int* returns, double* t_end, int* phase_end, double* acc, double* sec_t, double* sec_x,
    int* counts, double* ev_t, int* ev_code, double* ev_before, double* ev_after) {
  int N = dims[0], P = dims[1], E = dims[2], steps = dims[3], n_u = dims[4];
  int u_stride = dims[5], nmax = dims[6], cap = dims[7], p_stride = dims[8];
  int n0 = phase_dims[0];
  double rtol = opts[0], atol = opts[1], max_time = opts[2];
  int s, i, k, code = 0, opened = 0;
  gaitopt_call *ev_calls = 0, *exc_calls = 0, *start_calls = 0, *reset_calls = 0;
  char *have_start = 0, *have_reset = 0;
  double *state = 0, *stamps = 0, *ends = 0, *yold = 0, *F = 0, *hit = 0, *x = 0, *xn = 0;
  double *ev = 0, *g1 = 0, *g2 = 0, *cv = 0, *cr = 0, times[GAITOPT_ZENO_KEEP];
  int *adims = 0, *at_end = 0;
  ev_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  exc_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  start_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  reset_calls = (gaitopt_call*)calloc((size_t)P * E, sizeof(gaitopt_call));
  have_start = (char*)calloc(P, 1);
  have_reset = (char*)calloc((size_t)P * E, 1);
  state = (double*)calloc(4 + 2 * nmax + 2 * E, sizeof(double));
  stamps = (double*)calloc(GAITOPT_CAP, sizeof(double));
  ends = (double*)calloc(GAITOPT_CAP, sizeof(double));
  yold = (double*)calloc((size_t)GAITOPT_CAP * nmax, sizeof(double));
  F = (double*)calloc((size_t)GAITOPT_CAP * 7 * nmax, sizeof(double));
  hit = (double*)calloc(1 + nmax, sizeof(double));
  x = (double*)calloc(nmax, sizeof(double));
  xn = (double*)calloc(nmax, sizeof(double));
  ev = (double*)calloc(5 * E + 1, sizeof(double));
  adims = (int*)calloc((size_t)P * 3, sizeof(int));
  at_end = (int*)calloc((size_t)P * E + 1, sizeof(int));
  if (!(ev_calls && exc_calls && start_calls && reset_calls && have_start && have_reset &&
        state && stamps && ends && yold && F && hit && x && xn && ev && adims && at_end)) {
    code = -1;
    goto done;
  }
  g1 = ev + E; g2 = g1 + E; cv = g2 + E; cr = cv + E;
  for (i = 0; i < P; i++) { /* open every phase's calls once */
    void** t = fns + 10 * i;
    if (gaitopt_open(&ev_calls[i], t[2], t[3])) { code = -1; goto done; }
    if (gaitopt_open(&exc_calls[i], t[8], t[9])) {
      gaitopt_close(&ev_calls[i]);
      code = -1;
      goto done;
    }
    opened = i + 1;
    if (starts[2 * i]) {
      if (gaitopt_open(&start_calls[i], starts[2 * i], starts[2 * i + 1])) { code = -1; goto done; }
      have_start[i] = 1;
    }
    for (k = 0; k < E; k++)
      if (resets[2 * (i * E + k)]) {
        if (gaitopt_open(&reset_calls[i * E + k], resets[2 * (i * E + k)],
                         resets[2 * (i * E + k) + 1])) { code = -1; goto done; }
        have_reset[i * E + k] = 1;
      }
    adims[3 * i] = phase_dims[4 * i];
    adims[3 * i + 1] = phase_dims[4 * i + 1];
    adims[3 * i + 2] = phase_dims[4 * i + 2];
    for (k = 0; k < E; k++) at_end[i * E + k] = flags[2 * (i * E + k) + 1];
  }

  for (s = 0; s < N; s++) {
    const double* us = u + (size_t)s * u_stride;
    const double* p = p_all + (size_t)s * p_stride;
    double t = 0.0;
    int phase = 0, ret = 0, n_imp = 0, count = 0, st = status[s];
    double* srow_t = sec_t + (size_t)s * (steps + 1);
    double* srow_x = sec_x + (size_t)s * (steps + 1) * n0;
    (void)n_u;
    last[s] = -1; acc[s] = NAN; returns[s] = 0;
    if (cap > 0) counts[s] = 0;
    if (st != B_RUNNING) { t_end[s] = 0.0; phase_end[s] = 0; continue; }
    memcpy(x, x0 + (size_t)s * n0, n0 * sizeof(double));
    srow_t[0] = 0.0;
    memcpy(srow_x, x, n0 * sizeof(double));
#define GAITOPT_EVENT(TT, CODE, BEFORE, NB, AFTER, NA)                                       \
    do {                                                                                     \
      if (cap > 0) {                                                                         \
        if (count >= cap) { st = B_OVERFLOW; goto ended; }                                   \
        size_t r_ = (size_t)s * cap + count;                                                 \
        ev_t[r_] = (TT); ev_code[r_] = (CODE);                                               \
        for (i = 0; i < nmax; i++) {                                                         \
          ev_before[r_ * nmax + i] = i < (NB) ? (BEFORE)[i] : NAN;                           \
          ev_after[r_ * nmax + i] = ((AFTER) && i < (NA)) ? (AFTER)[i] : NAN;                \
        }                                                                                    \
        count++;                                                                             \
      }                                                                                      \
    } while (0)
    while (ret < steps || (phase != 0 && steps > 0)) {
      const int* pd = phase_dims + 4 * phase;
      int n = pd[0], n_tr = pd[2], n_c = pd[3], fired, arc;
      const int* tr = trans + 3 * phase * E;
      const double* dr = dirs + phase * E;
      /* PhaseFunctions.violated_at_start: the first constraint that fails where it begins */
      if (n_c > 0 && have_start[phase]) {
        int bad = -1;
        if (gaitopt_xup2(&start_calls[phase], x, us, p, cv, cr)) { code = -1; goto done; }
        for (k = 0; k < n_c && bad < 0; k++) {
          if (flags[2 * (phase * E + k)]) { if (!(cr[k] > GAITOPT_RATE)) bad = k; }
          else if (cv[k] < -GAITOPT_AT_END) bad = k;
        }
        if (bad >= 0) {
          GAITOPT_EVENT(t, phase * E + n_tr + bad, x, n, (double*)0, 0);
          last[s] = phase * E + n_tr + bad;
          st = B_FELL;
          break;
        }
      }
      /* _rests_on_guard, where a step is still to come */
      if (ret < steps) {
        int rest = 0, rates = 0;
        if (gaitopt_xup(&ev_calls[phase], x, us, p, ev)) { code = -1; goto done; }
        for (k = 0; k < n_tr && !rest; k++) {
          if (tr[3 * k + 1] || fabs(dr[k] * ev[k]) > GAITOPT_ARM) continue;
          if (!rates && gaitopt_xup2(&exc_calls[phase], x, us, p, g1, g2)) { code = -1; goto done; }
          rates = 1;
          if (fabs(g1[k]) <= GAITOPT_ARM && g2[k] > 0) rest = 1;
        }
        if (rest) { acc[s] = t; st = B_STANDING; break; }
      }
      /* the arc (compiled.py: integrate_arc) */
      {
        double aopts[4];
        int taken = 0, event = -1;
        aopts[0] = rtol; aopts[1] = atol; aopts[2] = t; aopts[3] = t + max_time;
        memset(state, 0, (4 + 2 * nmax + 2 * E) * sizeof(double));
        state[0] = t; state[1] = -1.0;
        memcpy(state + 4, x, n * sizeof(double));
        do {
          arc = gaitopt_arc(fns + 10 * phase, adims + 3 * phase, us, p, dr, at_end + phase * E,
                            aopts, state, GAITOPT_CAP, stamps, ends, yold, F, &taken, hit,
                            &event);
        } while (arc == 3);
        if (arc < 0) { code = -1; goto done; }
        if (arc == 1 || arc == 2) { /* timeout, or the integrator failed */
          t = state[0];
          st = arc == 1 ? B_TIMEOUT : B_FAILED;
          break;
        }
        t = hit[0];
        fired = event;
      }
      if (fired >= n_tr || tr[3 * fired + 1]) { /* a unilateral constraint, a terminal event */
        GAITOPT_EVENT(t, phase * E + fired, hit + 1, n, (double*)0, 0);
        last[s] = phase * E + fired;
        st = B_FELL;
        break;
      }
      {
        int target = tr[3 * fired], nt = phase_dims[4 * target];
        if (!have_reset[phase * E + fired]) { code = -1; goto done; }
        if (gaitopt_xup(&reset_calls[phase * E + fired], hit + 1, us, p, xn)) {
          code = -1;
          goto done;
        }
        GAITOPT_EVENT(t, phase * E + fired, hit + 1, n, xn, nt);
        memcpy(x, xn, nt * sizeof(double));
        if (tr[3 * fired + 2]) {
          ret++;
          srow_t[ret] = t;
          memcpy(srow_x + (size_t)ret * n0, x, n0 * sizeof(double));
        }
        phase = target;
      }
      /* an accumulation of impacts (zeno.py) */
      if (n_imp == GAITOPT_ZENO_KEEP) memmove(times, times + 1, (n_imp - 1) * sizeof(double));
      else n_imp++;
      times[n_imp - 1] = t;
      {
        double when = NAN;
        if (gaitopt_zeno(times, n_imp, &when) && ret < steps) {
          acc[s] = when;
          st = B_STANDING;
          break;
        }
      }
    }
  ended:
    if (st == B_RUNNING) st = B_COMPLETED;
    status[s] = st;
    returns[s] = ret;
    t_end[s] = t;
    phase_end[s] = phase;
    if (cap > 0) counts[s] = count;
  }
#undef GAITOPT_EVENT
done:
  for (i = 0; i < opened; i++) {
    gaitopt_close(&ev_calls[i]);
    gaitopt_close(&exc_calls[i]);
  }
  for (i = 0; i < P; i++) {
    if (have_start && have_start[i]) gaitopt_close(&start_calls[i]);
    for (k = 0; k < E; k++)
      if (have_reset && have_reset[i * E + k]) gaitopt_close(&reset_calls[i * E + k]);
  }
  free(ev_calls); free(exc_calls); free(start_calls); free(reset_calls);
  free(have_start); free(have_reset); free(state); free(stamps); free(ends); free(yold);
  free(F); free(hit); free(x); free(xn); free(ev); free(adims); free(at_end);
  return code;
}
"""

#: The batch library's whole source: CasADi's default types, the arc driver, the batch loop, the
#: lane driver (:mod:`gaitopt.kernels.lane_driver`: the same loop, several starts per step call).
SOURCE = _PRELUDE + DRIVER + BATCH + LANES_SOURCE


@lru_cache(maxsize=1)
def _library(verbose: bool = True):
    """The (cached) compiled batch library, a ``ctypes.CDLL``, or None (:func:`batch_library`)."""
    cc = compiler()
    if cc is None:
        return None
    library = cache_dir() / f"gaitopt_batch_driver_{_key(SOURCE, cc)}.so"
    try:
        if not library.exists():
            _compile(SOURCE, cc, library, "gaitopt_batch_driver", verbose)
        return ctypes.CDLL(str(library))
    except (OSError, subprocess.SubprocessError) as exc:
        if verbose:
            print(f"gaitopt: could not compile the batch driver ({exc}); batching in NumPy",
                  file=sys.stderr)  # fmt: skip
        return None


def lanes_library(verbose: bool = True):
    """``gaitopt_lanes`` of the batch library (:mod:`gaitopt.kernels.lane_driver`; the arguments
    of ``gaitopt_batch`` and then the phases' vector steps and ``(n_p, len(dims))``), a
    ``ctypes`` function, or None where the library is not there."""
    lib = _library(verbose)
    if lib is None:
        return None
    run = lib.gaitopt_lanes
    run.restype = ctypes.c_int
    run.argtypes = [ctypes.c_void_p] * 27
    return run


def batch_library(verbose: bool = True):
    """``gaitopt_batch`` of the (cached) compiled batch library, a ``ctypes`` function, or None
    where there is no C compiler (or ``GAITOPT_COMPILE=0``) or compiling fails: the batch
    simulation then steps its starts from NumPy (:mod:`gaitopt.simulation.batch_phase`)."""
    lib = _library(verbose)
    if lib is None:
        return None
    run = lib.gaitopt_batch
    run.restype = ctypes.c_int
    run.argtypes = [ctypes.c_void_p] * 25
    return run
