"""The per-lane state machine of the lane driver (:mod:`gaitopt.kernels.lane_driver`), C source.

A lane (``gaitopt_lane``) is one start in flight; ``gaitopt_run`` holds what all lanes share (the
batch's arrays, the phases' opened calls, the vector step's input and output arrays).  The
functions are ``gaitopt_batch``'s loop over a start's phases
(:mod:`gaitopt.kernels.batch_driver`) and ``gaitopt_arc``'s loop over an arc's steps
(:mod:`gaitopt.kernels.arc_driver`) cut where the step is called: ``gaitopt_lane_try`` writes a
step try's inputs into the lane's column and returns; ``gaitopt_lane_after`` takes the lane's
column of the results and goes on — accept or reject, crossings, Brent's root on the lane's
dense output, the reset and the section (``gaitopt_lane_event``), the next phase's checks and
arc start (``gaitopt_lane_top``) — until the lane waits for its next try or its start has ended
(``gaitopt_lane_end``), when ``gaitopt_lane_take`` gives it the batch's next start.  Statement for
statement the scalar drivers' code, with their helpers (the same translation unit).
"""

from __future__ import annotations

from .vector_step import LANES

__all__ = ["LANE_STATE"]

_SOURCE = r"""
/* ---- gaitopt lane state (gaitopt/kernels/lane_state.py) -------------------------------- */
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
    for (k = 0; k < n_tr; k++) /* _short_excursion: tau/4 with tau = 2|g1|/g2, where the */
      if (!armed[k] && g1[k] < 0 && 0 < g2[k] && /* excursion passes half the arming depth */
          values[k] - 0.5 * g1[k] * g1[k] / g2[k] < -0.5 * GAITOPT_ARM)
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
"""

#: The lanes' types and state machine (GAITOPT_W = :data:`~gaitopt.kernels.vector_step.LANES`).
LANE_STATE = _SOURCE.replace("@W@", str(LANES))
