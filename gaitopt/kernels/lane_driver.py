"""The C source of the lane driver ``gaitopt_lanes``: the batch of ``gaitopt_batch``
(:mod:`gaitopt.kernels.batch_driver`) with :data:`~gaitopt.kernels.vector_step.LANES` starts in
flight, their step tries made by one call of the model's vector step
(:mod:`gaitopt.kernels.vector_step`).

Each lane is one start with its own time, step size, phase, step count, event state and event
record; the driver is ``gaitopt_batch``'s loop over starts and ``gaitopt_arc``'s loop over steps
turned inside out into a state machine per lane (:data:`LANES_SOURCE`):

* a lane waiting for a step try has written its ``y``, ``f``, ``h``, ``u`` and ``p`` into its
  column of its phase's input arrays; each round calls each phase's vector step once for all the
  lanes waiting in that phase (the other columns hold a copy of a waiting lane's inputs);
* after the call each of those lanes takes its column of the results and goes on alone, in
  scalar code and in the scalar driver's order: the error norm's accept or reject and the new
  step size, the directional crossings on the check points, their confirmation and Brent's root
  on the lane's dense output, admissibility, the reset, the section, the accumulation of impacts,
  the constraint check and the guard test where the next phase begins, the next arc's start (rate,
  initial step, arming, excursion bound) — until it waits for its next try, or its start has
  ended, when it takes the next start of the batch.

The scalar code is ``gaitopt_arc``'s and ``gaitopt_batch``'s, statement for statement (the
helpers — dense output, Brent, ``locate_crossing``, admissibility, the initial step, the Zeno
test — are theirs, in the same translation unit), and the vector step gives each lane the scalar
step's bits, so every start ends as in ``gaitopt_batch`` to the bit (tested,
``tests/test_simulation_batch_lanes.py``).  Per-start inputs and parameters: ``u_stride``
(``dims[5]``) and ``p_stride`` (``dims[8]``; 0: one parameter vector for all starts) as in
``gaitopt_batch``.
"""

from __future__ import annotations

from .vector_step import LANES

__all__ = ["LANES_SOURCE"]


_SOURCE = r"""
/* ---- gaitopt lane driver (gaitopt/kernels/lane_driver.py) ------------------------------ */
#define GAITOPT_W @W@
typedef int (*gaitopt_vfn)(const double**, double**);

typedef struct {
  int lane;   /* its column in the vector step's arrays */
  int s;      /* the start, -1: none */
  int pend;   /* the phase whose vector step this lane waits for, -1: none */
  int st, phase, ret, n_imp, count;
  double t, times[GAITOPT_ZENO_KEEP];
  const double *us, *ps;
  /* the arc: gaitopt_arc's state array (t, h_abs, max_step, short, y, f, values, armed) and
     its step try */
  double *state, t0, t_bound, tt, h_abs, min_step, t_new;
  int rejected;
  double *x, *xn, *hit, *yold, *F, *G, *sg, *y_new, *f_new, *work, *xt, *xh, *ev, *admv;
  double *cv, *cr, *g1, *g2;
} gaitopt_lane;

typedef struct {
  int N, P, E, steps, nmax, cap, u_stride, p_stride, n_u, n_p, next;
  double rtol, atol, max_time, frac[GAITOPT_CHECKS - 1];
  const int *phase_dims, *trans, *flags;
  const double *dirs, *u, *p, *x0;
  gaitopt_call *ev_calls, *adm_calls, *flow_calls, *exc_calls, *start_calls, *reset_calls;
  char *have_start, *have_reset;
  int* at_end;
  gaitopt_vfn* vstep;
  double** vin;  /* per phase 7 inputs (y, f, h, fractions, u, p, tol), nnz x GAITOPT_W each */
  double** vout; /* per phase 5 outputs (y_new, f_new, error, F, G) */
  int *status, *last, *returns, *phase_end, *counts, *ev_code;
  double *t_end, *acc, *sec_t, *sec_x, *ev_t, *ev_before, *ev_after;
} gaitopt_run;

/* a lane's context for gaitopt_arc's scalar helpers (dense output, events, Brent) */
static void gaitopt_lane_ctx(gaitopt_run* R, gaitopt_lane* L, gaitopt_ctx* c) {
  const int* pd = R->phase_dims + 4 * L->phase;
  memset(c, 0, sizeof(*c));
  c->events = R->ev_calls[L->phase]; c->adm = R->adm_calls[L->phase];
  c->flow = R->flow_calls[L->phase]; c->excursion = R->exc_calls[L->phase];
  c->n = pd[0]; c->m = pd[1]; c->n_tr = pd[2];
  c->u = L->us; c->p = L->ps; c->dirs = R->dirs + L->phase * R->E;
  c->at_end = R->at_end + L->phase * R->E;
  c->ev = L->ev; c->xt = L->xt; c->admv = L->admv;
}

/* gaitopt_batch's GAITOPT_EVENT: 1 where the start's buffer is full (overflow) */
static int gaitopt_lane_record(gaitopt_run* R, gaitopt_lane* L, double tt, int code,
                               const double* before, int nb, const double* after, int na) {
  size_t r;
  int i;
  if (R->cap <= 0) return 0;
  if (L->count >= R->cap) return 1;
  r = (size_t)L->s * R->cap + L->count;
  R->ev_t[r] = tt; R->ev_code[r] = code;
  for (i = 0; i < R->nmax; i++) {
    R->ev_before[r * R->nmax + i] = i < nb ? before[i] : NAN;
    R->ev_after[r * R->nmax + i] = (after && i < na) ? after[i] : NAN;
  }
  L->count++;
  return 0;
}

/* the start has ended (gaitopt_batch's `ended:`) */
static void gaitopt_lane_end(gaitopt_run* R, gaitopt_lane* L) {
  int s = L->s;
  if (L->st == B_RUNNING) L->st = B_COMPLETED;
  R->status[s] = L->st; R->returns[s] = L->ret; R->t_end[s] = L->t;
  R->phase_end[s] = L->phase;
  if (R->cap > 0) R->counts[s] = L->count;
  L->s = -1; L->pend = -1;
}

/* one step try (gaitopt_arc's inner loop up to the step's call): the lane's column written */
static void gaitopt_lane_try(gaitopt_run* R, gaitopt_lane* L) {
  int q = L->phase, n = R->phase_dims[4 * q], i, l = L->lane;
  double hh, **in = R->vin + 7 * q, *y = L->state + 4, *f = y + n;
  if (L->h_abs < L->min_step) { /* gaitopt_arc's code 2: the step became too small */
    L->t = L->state[0];
    L->st = B_FAILED;
    gaitopt_lane_end(R, L);
    return;
  }
  L->t_new = L->tt + L->h_abs;
  if (L->t_new - L->t_bound > 0) L->t_new = L->t_bound;
  hh = L->t_new - L->tt;
  L->h_abs = fabs(hh);
  for (i = 0; i < n; i++) {
    in[0][i * GAITOPT_W + l] = y[i];
    in[1][i * GAITOPT_W + l] = f[i];
  }
  in[2][l] = hh;
  for (i = 0; i < R->n_u; i++) in[4][i * GAITOPT_W + l] = L->us[i];
  for (i = 0; i < R->n_p; i++) in[5][i * GAITOPT_W + l] = L->ps[i];
  L->pend = q;
}

/* a new step of the arc (CompiledDOP853._step_impl's start) */
static void gaitopt_lane_step(gaitopt_run* R, gaitopt_lane* L) {
  double tt = L->state[0];
  L->tt = tt;
  L->min_step = 10 * fabs(nextafter(tt, INFINITY) - tt);
  L->h_abs = gaitopt_min(gaitopt_max(L->state[1], L->min_step), L->state[2]);
  L->rejected = 0;
  gaitopt_lane_try(R, L);
}

/* gaitopt_batch's loop over phases from its top, up to the arc's first step try (or the end
   of the start).  0, or -1 where a function failed. */
static int gaitopt_lane_top(gaitopt_run* R, gaitopt_lane* L) {
  int E = R->E, phase = L->phase, k, n, n_tr, n_c, m;
  const int* pd;
  const int* tr;
  const double* dr;
  gaitopt_ctx c;
  double *state = L->state, *y, *f, *values, *armed, bound = INFINITY;
  if (!(L->ret < R->steps || (phase != 0 && R->steps > 0))) {
    gaitopt_lane_end(R, L);
    return 0;
  }
  pd = R->phase_dims + 4 * phase;
  n = pd[0]; m = pd[1]; n_tr = pd[2]; n_c = pd[3];
  tr = R->trans + 3 * phase * E;
  dr = R->dirs + phase * E;
  /* PhaseFunctions.violated_at_start */
  if (n_c > 0 && R->have_start[phase]) {
    int bad = -1;
    if (gaitopt_xup2(&R->start_calls[phase], L->x, L->us, L->ps, L->cv, L->cr)) return -1;
    for (k = 0; k < n_c && bad < 0; k++) {
      if (R->flags[2 * (phase * E + k)]) { if (!(L->cr[k] > GAITOPT_RATE)) bad = k; }
      else if (L->cv[k] < -GAITOPT_AT_END) bad = k;
    }
    if (bad >= 0) {
      if (gaitopt_lane_record(R, L, L->t, phase * E + n_tr + bad, L->x, n, 0, 0)) {
        L->st = B_OVERFLOW;
      } else {
        R->last[L->s] = phase * E + n_tr + bad;
        L->st = B_FELL;
      }
      gaitopt_lane_end(R, L);
      return 0;
    }
  }
  /* _rests_on_guard */
  if (L->ret < R->steps) {
    int rest = 0, rates = 0;
    if (gaitopt_xup(&R->ev_calls[phase], L->x, L->us, L->ps, L->ev)) return -1;
    for (k = 0; k < n_tr && !rest; k++) {
      if (tr[3 * k + 1] || fabs(dr[k] * L->ev[k]) > GAITOPT_ARM) continue;
      if (!rates && gaitopt_xup2(&R->exc_calls[phase], L->x, L->us, L->ps, L->g1, L->g2))
        return -1;
      rates = 1;
      if (fabs(L->g1[k]) <= GAITOPT_ARM && L->g2[k] > 0) rest = 1;
    }
    if (rest) {
      R->acc[L->s] = L->t;
      L->st = B_STANDING;
      gaitopt_lane_end(R, L);
      return 0;
    }
  }
  /* the arc: gaitopt_batch's call set-up and gaitopt_arc's start */
  L->t0 = L->t; L->t_bound = L->t + R->max_time;
  memset(state, 0, (4 + 2 * R->nmax + 2 * E) * sizeof(double));
  state[0] = L->t; state[1] = -1.0;
  memcpy(state + 4, L->x, n * sizeof(double));
  y = state + 4; f = y + n; values = f + n; armed = values + m;
  gaitopt_lane_ctx(R, L, &c);
  {
    double *g1 = L->sg, *g2 = L->sg + n_tr;
    if (gaitopt_xup(&c.flow, y, L->us, L->ps, f)) return -1;
    state[1] = gaitopt_initial_step(&c, state[0], L->t_bound, y, f, R->rtol, R->atol, L->work);
    gaitopt_xup(&c.events, y, L->us, L->ps, c.ev);
    for (k = 0; k < m; k++) {
      values[k] = dr[k] * c.ev[k];
      armed[k] = values[k] < -GAITOPT_ARM;
    }
    if (gaitopt_xup2(&c.excursion, y, L->us, L->ps, g1, g2)) return -1;
    for (k = 0; k < n_tr; k++) /* _short_excursion: tau/4 with tau = 2|g1|/g2 */
      if (!armed[k] && g1[k] < 0 && 0 < g2[k])
        bound = gaitopt_min(bound, 0.5 * fabs(g1[k]) / g2[k]);
    state[3] = (isfinite(bound) && bound > 0) ? bound : 0.0;
    state[2] = state[3] > 0 ? state[3] : INFINITY;
  }
  gaitopt_lane_step(R, L);
  return 0;
}

/* the arc ended at a crossing of event `fired` at hit (gaitopt_batch after gaitopt_arc) */
static int gaitopt_lane_event(gaitopt_run* R, gaitopt_lane* L, int fired) {
  int E = R->E, phase = L->phase, n = R->phase_dims[4 * phase], n_tr = R->phase_dims[4 * phase + 2];
  const int* tr = R->trans + 3 * phase * E;
  double when = NAN;
  L->t = L->hit[0];
  if (fired >= n_tr || tr[3 * fired + 1]) { /* a unilateral constraint, a terminal event */
    if (gaitopt_lane_record(R, L, L->t, phase * E + fired, L->hit + 1, n, 0, 0)) {
      L->st = B_OVERFLOW;
    } else {
      R->last[L->s] = phase * E + fired;
      L->st = B_FELL;
    }
    gaitopt_lane_end(R, L);
    return 0;
  }
  {
    int target = tr[3 * fired], nt = R->phase_dims[4 * target];
    if (!R->have_reset[phase * E + fired]) return -1;
    if (gaitopt_xup(&R->reset_calls[phase * E + fired], L->hit + 1, L->us, L->ps, L->xn))
      return -1;
    if (gaitopt_lane_record(R, L, L->t, phase * E + fired, L->hit + 1, n, L->xn, nt)) {
      L->st = B_OVERFLOW;
      gaitopt_lane_end(R, L);
      return 0;
    }
    memcpy(L->x, L->xn, nt * sizeof(double));
    if (tr[3 * fired + 2]) {
      int n0 = R->phase_dims[0];
      L->ret++;
      R->sec_t[(size_t)L->s * (R->steps + 1) + L->ret] = L->t;
      memcpy(R->sec_x + ((size_t)L->s * (R->steps + 1) + L->ret) * n0, L->x,
             n0 * sizeof(double));
    }
    L->phase = target;
  }
  /* an accumulation of impacts (zeno.py) */
  if (L->n_imp == GAITOPT_ZENO_KEEP)
    memmove(L->times, L->times + 1, (L->n_imp - 1) * sizeof(double));
  else
    L->n_imp++;
  L->times[L->n_imp - 1] = L->t;
  if (gaitopt_zeno(L->times, L->n_imp, &when) && L->ret < R->steps) {
    R->acc[L->s] = when;
    L->st = B_STANDING;
    gaitopt_lane_end(R, L);
    return 0;
  }
  return gaitopt_lane_top(R, L);
}

/* the lane's step try is back (gaitopt_arc after the step's call).  0, or -1. */
static int gaitopt_lane_after(gaitopt_run* R, gaitopt_lane* L) {
  int q = L->phase, E = R->E, l = L->lane, i, j, k;
  const int* pd = R->phase_dims + 4 * q;
  int n = pd[0], m = pd[1], n_tr = pd[2], crossing = 0, best = -1, finished;
  double **out = R->vout + 5 * q, err = out[2][l], tt = L->tt, t_new = L->t_new;
  double *state = L->state, *y = state + 4, *f = y + n, *values = f + n, *armed = values + m;
  double grid[GAITOPT_CHECKS + 1], best_t = 0.0;
  const double* dirs = R->dirs + q * E;
  gaitopt_ctx c;
  L->pend = -1;
  if (!(err < 1)) { /* rejected */
    L->h_abs *= gaitopt_max(GAITOPT_MIN_FACTOR, GAITOPT_SAFETY * pow(err, GAITOPT_EXPONENT));
    L->rejected = 1;
    gaitopt_lane_try(R, L);
    return 0;
  }
  {
    double factor = err == 0 ? GAITOPT_MAX_FACTOR
                             : gaitopt_min(GAITOPT_MAX_FACTOR,
                                           GAITOPT_SAFETY * pow(err, GAITOPT_EXPONENT));
    if (L->rejected) factor = gaitopt_min(1, factor);
    L->h_abs *= factor;
  }
  /* the step is taken: its dense output (the lane's columns) */
  memcpy(L->yold, y, n * sizeof(double));
  for (i = 0; i < n; i++) {
    L->y_new[i] = out[0][i * GAITOPT_W + l];
    L->f_new[i] = out[1][i * GAITOPT_W + l];
  }
  for (i = 0; i < m * GAITOPT_CHECKS; i++) L->G[i] = out[4][i * GAITOPT_W + l];
  finished = t_new - L->t_bound >= 0;
  for (j = 0; j <= GAITOPT_CHECKS; j++) grid[j] = j * ((t_new - tt) / GAITOPT_CHECKS) + tt;
  grid[GAITOPT_CHECKS] = t_new;
  for (k = 0; k < m; k++)
    for (j = 0; j < GAITOPT_CHECKS; j++) {
      double s = dirs[k] * L->G[j * m + k];
      double before = j ? L->sg[k * GAITOPT_CHECKS + j - 1] : values[k];
      L->sg[k * GAITOPT_CHECKS + j] = s;
      if (before < 0 && s >= 0) crossing = 1;
    }
  if (!crossing) {
    for (k = 0; k < m; k++) {
      for (j = 0; j < GAITOPT_CHECKS; j++)
        if (L->sg[k * GAITOPT_CHECKS + j] < -GAITOPT_ARM) armed[k] = 1;
      values[k] = L->sg[k * GAITOPT_CHECKS + GAITOPT_CHECKS - 1];
    }
  } else { /* the lane's context for the dense output and the events (built only here) */
    for (i = 0; i < 7 * n; i++) L->F[i] = out[3][i * GAITOPT_W + l];
    gaitopt_lane_ctx(R, L, &c);
    c.F = L->F; c.yold = L->yold; c.t_old = tt; c.t_new = t_new;
    for (k = 0; k < m; k++) {
      double previous = values[k];
      int was_armed = armed[k] != 0;
      for (j = 1; j <= GAITOPT_CHECKS; j++) {
        double current = L->sg[k * GAITOPT_CHECKS + j - 1];
        if (was_armed && previous < 0 && 0 <= current) { /* confirm on the dense output */
          double a = gaitopt_g(&c, k, grid[j - 1]);
          double b = j < GAITOPT_CHECKS ? gaitopt_g(&c, k, grid[j])
                                        : gaitopt_signed(&c, k, L->y_new);
          previous = a; current = b;
        }
        if (was_armed && previous < 0 && 0 <= current) {
          double th = gaitopt_locate(&c, k, grid[j - 1], grid[j]);
          gaitopt_dense(&c, th, L->xh);
          if (gaitopt_admissible(&c, k, L->xh)) {
            if (best < 0 || th < best_t) {
              best = k; best_t = th;
              L->hit[0] = th;
              memcpy(L->hit + 1, L->xh, n * sizeof(double));
            }
            break;
          }
        }
        was_armed = was_armed || current < -GAITOPT_ARM;
        previous = current;
      }
      armed[k] = was_armed;
      values[k] = previous;
    }
  }
  /* the step becomes the solver's state */
  state[0] = t_new; state[1] = L->h_abs;
  memcpy(y, L->y_new, n * sizeof(double));
  memcpy(f, L->f_new, n * sizeof(double));
  if (state[3] > 0) {
    int all = 1;
    for (k = 0; k < n_tr; k++) all = all && armed[k] != 0;
    if (all || t_new - L->t0 > 8 * state[3]) { state[2] = INFINITY; state[3] = 0.0; }
  }
  if (best >= 0) return gaitopt_lane_event(R, L, best);
  if (finished) { /* gaitopt_arc's code 1: the phase's time ran out */
    L->t = state[0];
    L->st = B_TIMEOUT;
    gaitopt_lane_end(R, L);
    return 0;
  }
  gaitopt_lane_step(R, L);
  return 0;
}

/* the lane takes starts until one waits for a step try or none is left.  0, or -1. */
static int gaitopt_lane_take(gaitopt_run* R, gaitopt_lane* L) {
  while (L->s < 0 && R->next < R->N) {
    int s = R->next++, n0 = R->phase_dims[0];
    L->s = s; L->pend = -1;
    L->us = R->u + (size_t)s * R->u_stride;
    L->ps = R->p + (size_t)s * R->p_stride;
    L->t = 0.0; L->phase = 0; L->ret = 0; L->n_imp = 0; L->count = 0; L->st = R->status[s];
    R->last[s] = -1; R->acc[s] = NAN; R->returns[s] = 0;
    if (R->cap > 0) R->counts[s] = 0;
    if (L->st != B_RUNNING) {
      R->t_end[s] = 0.0; R->phase_end[s] = 0;
      L->s = -1;
      continue;
    }
    memcpy(L->x, R->x0 + (size_t)s * n0, n0 * sizeof(double));
    R->sec_t[(size_t)s * (R->steps + 1)] = 0.0;
    memcpy(R->sec_x + (size_t)s * (R->steps + 1) * n0, L->x, n0 * sizeof(double));
    if (gaitopt_lane_top(R, L)) return -1;
  }
  return 0;
}

/*
  gaitopt_batch's many starts (its arguments, the same meaning) with GAITOPT_W in flight, one
  vector step call per phase and round (module docstring).  dims may carry a 9th entry,
  p_stride (0: one parameter vector for all starts, else n_p); lane_dims: n_p (the parameters of
  one start), the number of dims entries (8 or 9).  vsteps (phases): each phase's vector step
  (gaitopt_vstep_i_c or _g: int f(const double** arg, double** res)).
  Returns 0, or -1 where a function failed or memory ran out.
*/
CASADI_SYMBOL_EXPORT int gaitopt_lanes(
    const int* dims, const int* phase_dims, const int* trans, const int* flags,
    const double* dirs, void** fns, void** resets, void** starts, const double* u,
    const double* p, const double* opts, const double* x0, int* status, int* last,
    int* returns, double* t_end, int* phase_end, double* acc, double* sec_t, double* sec_x,
    int* counts, double* ev_t, int* ev_code, double* ev_before, double* ev_after,
    void** vsteps, const int* lane_dims) {
  gaitopt_run R;
  gaitopt_lane lanes[GAITOPT_W];
  int P = dims[1], E = dims[2], nmax = dims[6], i, k, l, q, code = 0, opened = 0, active;
  size_t per_lane = (4 + 2 * nmax + 2 * E) + 2 * nmax + (1 + nmax) + 8 * nmax
                    + 2 * E * GAITOPT_CHECKS + 2 * E + 4 * nmax + 2 * nmax + 2 * nmax
                    + 2 * E + 4 * E + 8;
  double* block = 0;
  memset(&R, 0, sizeof(R));
  memset(lanes, 0, sizeof(lanes));
  R.N = dims[0]; R.P = P; R.E = E; R.steps = dims[3]; R.n_u = dims[4]; R.u_stride = dims[5];
  R.nmax = nmax; R.cap = dims[7]; R.p_stride = lane_dims[1] > 8 ? dims[8] : 0;
  R.n_p = lane_dims[0];
  R.rtol = opts[0]; R.atol = opts[1]; R.max_time = opts[2];
  for (i = 0; i < GAITOPT_CHECKS - 1; i++) R.frac[i] = (double)(i + 1) / GAITOPT_CHECKS;
  R.phase_dims = phase_dims; R.trans = trans; R.flags = flags; R.dirs = dirs; R.u = u; R.p = p;
  R.x0 = x0; R.status = status; R.last = last; R.returns = returns; R.t_end = t_end;
  R.phase_end = phase_end; R.acc = acc; R.sec_t = sec_t; R.sec_x = sec_x; R.counts = counts;
  R.ev_t = ev_t; R.ev_code = ev_code; R.ev_before = ev_before; R.ev_after = ev_after;
  R.vstep = (gaitopt_vfn*)vsteps;
  R.ev_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  R.adm_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  R.flow_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  R.exc_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  R.start_calls = (gaitopt_call*)calloc(P, sizeof(gaitopt_call));
  R.reset_calls = (gaitopt_call*)calloc((size_t)P * E, sizeof(gaitopt_call));
  R.have_start = (char*)calloc(P, 1);
  R.have_reset = (char*)calloc((size_t)P * E, 1);
  R.at_end = (int*)calloc((size_t)P * E + 1, sizeof(int));
  R.vin = (double**)calloc((size_t)7 * P, sizeof(double*));
  R.vout = (double**)calloc((size_t)5 * P, sizeof(double*));
  block = (double*)calloc(per_lane * GAITOPT_W, sizeof(double));
  if (!(R.ev_calls && R.adm_calls && R.flow_calls && R.exc_calls && R.start_calls &&
        R.reset_calls && R.have_start && R.have_reset && R.at_end && R.vin && R.vout && block)) {
    code = -1;
    goto done;
  }
  for (l = 0; l < GAITOPT_W; l++) { /* each lane's scalar arrays */
    gaitopt_lane* L = lanes + l;
    double* w = block + per_lane * l;
    L->lane = l; L->s = -1; L->pend = -1;
    L->state = w; w += 4 + 2 * nmax + 2 * E;
    L->x = w; w += nmax; L->xn = w; w += nmax;
    L->hit = w; w += 1 + nmax;
    L->yold = w; w += nmax; L->F = w; w += 7 * nmax;
    L->G = w; w += E * GAITOPT_CHECKS; L->sg = w; w += E * GAITOPT_CHECKS + 2 * E;
    L->work = w; w += 4 * nmax;
    L->y_new = w; w += nmax; L->f_new = w; w += nmax;
    L->xt = w; w += nmax; L->xh = w; w += nmax;
    L->ev = w; w += E; L->admv = w; w += E;
    L->cv = w; w += E; L->cr = w; w += E; L->g1 = w; w += E; L->g2 = w; w += E;
  }
  for (i = 0; i < P; i++) { /* open every phase's calls once; the vector step's arrays */
    void** t = fns + 10 * i;
    const int* pd = phase_dims + 4 * i;
    int sizes[12], j;
    if (gaitopt_open(&R.ev_calls[i], t[2], t[3])) { code = -1; goto done; }
    if (gaitopt_open(&R.adm_calls[i], t[4], t[5])) {
      gaitopt_close(&R.ev_calls[i]); code = -1; goto done;
    }
    if (gaitopt_open(&R.flow_calls[i], t[6], t[7])) {
      gaitopt_close(&R.ev_calls[i]); gaitopt_close(&R.adm_calls[i]); code = -1; goto done;
    }
    if (gaitopt_open(&R.exc_calls[i], t[8], t[9])) {
      gaitopt_close(&R.ev_calls[i]); gaitopt_close(&R.adm_calls[i]);
      gaitopt_close(&R.flow_calls[i]); code = -1; goto done;
    }
    opened = i + 1;
    if (starts[2 * i]) {
      if (gaitopt_open(&R.start_calls[i], starts[2 * i], starts[2 * i + 1])) {
        code = -1; goto done;
      }
      R.have_start[i] = 1;
    }
    for (k = 0; k < E; k++) {
      if (resets[2 * (i * E + k)]) {
        if (gaitopt_open(&R.reset_calls[i * E + k], resets[2 * (i * E + k)],
                         resets[2 * (i * E + k) + 1])) { code = -1; goto done; }
        R.have_reset[i * E + k] = 1;
      }
      R.at_end[i * E + k] = flags[2 * (i * E + k) + 1];
    }
    sizes[0] = pd[0]; sizes[1] = pd[0]; sizes[2] = 1; sizes[3] = GAITOPT_CHECKS - 1;
    sizes[4] = R.n_u; sizes[5] = R.n_p; sizes[6] = 2;
    sizes[7] = pd[0]; sizes[8] = pd[0]; sizes[9] = 1; sizes[10] = 7 * pd[0];
    sizes[11] = pd[1] * GAITOPT_CHECKS;
    for (j = 0; j < 12; j++) {
      double* a = (double*)calloc((size_t)(sizes[j] > 0 ? sizes[j] : 1) * GAITOPT_W,
                                  sizeof(double));
      if (!a) { code = -1; goto done; }
      if (j < 7) R.vin[7 * i + j] = a; else R.vout[5 * i + j - 7] = a;
    }
    for (l = 0; l < GAITOPT_W; l++) {
      for (j = 0; j < GAITOPT_CHECKS - 1; j++) R.vin[7 * i + 3][j * GAITOPT_W + l] = R.frac[j];
      R.vin[7 * i + 6][l] = R.rtol;
      R.vin[7 * i + 6][GAITOPT_W + l] = R.atol;
    }
  }
  for (l = 0; l < GAITOPT_W; l++)
    if (gaitopt_lane_take(&R, lanes + l)) { code = -1; goto done; }
  do { /* rounds: per phase one vector step for the lanes waiting in it */
    active = 0;
    for (q = 0; q < P; q++) {
      int waiting = -1, j;
      for (l = 0; l < GAITOPT_W; l++)
        if (lanes[l].s >= 0 && lanes[l].pend == q) { waiting = l; break; }
      if (waiting < 0) continue;
      active = 1;
      for (l = 0; l < GAITOPT_W; l++) { /* the idle columns: a copy of a waiting lane's */
        if (lanes[l].s >= 0 && lanes[l].pend == q) continue;
        for (j = 0; j < 7; j++) {
          int rows = j == 0 || j == 1 ? phase_dims[4 * q] : j == 2 ? 1 : j == 4 ? R.n_u
                     : j == 5 ? R.n_p : 0;
          for (k = 0; k < rows; k++)
            R.vin[7 * q + j][k * GAITOPT_W + l] = R.vin[7 * q + j][k * GAITOPT_W + waiting];
        }
      }
      if (R.vstep[q]((const double**)(R.vin + 7 * q), R.vout + 5 * q)) { code = -1; goto done; }
      for (l = 0; l < GAITOPT_W; l++) {
        gaitopt_lane* L = lanes + l;
        if (L->s < 0 || L->pend != q) continue;
        if (gaitopt_lane_after(&R, L)) { code = -1; goto done; }
        if (L->s < 0 && gaitopt_lane_take(&R, L)) { code = -1; goto done; }
      }
    }
    for (l = 0; l < GAITOPT_W && !active; l++) active = lanes[l].s >= 0;
  } while (active);
done:
  for (i = 0; i < opened; i++) {
    gaitopt_close(&R.ev_calls[i]); gaitopt_close(&R.adm_calls[i]);
    gaitopt_close(&R.flow_calls[i]); gaitopt_close(&R.exc_calls[i]);
  }
  for (i = 0; i < P; i++) {
    if (R.have_start && R.have_start[i]) gaitopt_close(&R.start_calls[i]);
    for (k = 0; k < E; k++)
      if (R.have_reset && R.have_reset[i * E + k]) gaitopt_close(&R.reset_calls[i * E + k]);
  }
  if (R.vin) for (i = 0; i < 7 * P; i++) free(R.vin[i]);
  if (R.vout) for (i = 0; i < 5 * P; i++) free(R.vout[i]);
  free(R.ev_calls); free(R.adm_calls); free(R.flow_calls); free(R.exc_calls);
  free(R.start_calls); free(R.reset_calls); free(R.have_start); free(R.have_reset);
  free(R.at_end); free(R.vin); free(R.vout); free(block);
  return code;
}
"""

#: The lane driver's C (appended to the batch driver's source: it uses its helpers).
LANES_SOURCE = _SOURCE.replace("@W@", str(LANES))
