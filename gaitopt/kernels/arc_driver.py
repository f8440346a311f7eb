"""The C source of the compiled simulation's arc driver (:mod:`gaitopt.kernels.arcs`).

It is appended to the CasADi-generated C of a model class's phase functions and compiled with
them into one library; :func:`gaitopt.kernels.arcs.arc_library` calls ``gaitopt_arc`` through
``ctypes``.  One call integrates one phase (an *arc*) until an admissible directional crossing,
the same algorithm as :func:`gaitopt.simulation.phase.integrate_phase` with
:class:`gaitopt.dop853.CompiledDOP853`, step for step:

* SciPy's DOP853 start-up (``select_initial_step``; Hairer, Nørsett & Wanner, *Solving ODEs I*,
  §II.4) and step-size control (safety 0.9, factors 0.2…10, exponent −1/8, a step after a
  rejection not enlarged, the minimum step 10 ulp of ``t``);
* each step try one call of the generated DOP853 step (new state and rate, error norm, the 7
  dense-output coefficient vectors, the events at the step's interior check points and end);
* strict directional crossings: an event fires where its signed value goes from negative to
  non-negative after having been below ``-ARM`` in this arc; a sign change at the check points
  is confirmed on the dense output, the root located there by Brent's method (R. P. Brent,
  *Algorithms for Minimization without Derivatives*, 1973, ch. 4, as SciPy's ``brentq``;
  ``xtol`` 1e-15, ``rtol`` 4 eps) with :func:`~gaitopt.simulation.phase.locate_crossing`'s three
  end cases, and the crossing kept where the transition's rule admits it;
* the short-excursion step bound of :func:`gaitopt.simulation.phase._short_excursion`.

The state of the integration lives in the caller's arrays (``state``), so that a call that
fills the caller's step buffers returns (code 3) and the next call goes on where it stopped.
"""

__all__ = ["DRIVER"]

DRIVER = r"""
/* ---- gaitopt arc driver (gaitopt/kernels/arc_driver.py) ---------------------------------- */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef int (*gaitopt_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);
typedef int (*gaitopt_work_fn)(casadi_int*, casadi_int*, casadi_int*, casadi_int*);

typedef struct {
  gaitopt_fn f;
  const casadi_real** arg;
  casadi_real** res;
  casadi_int* iw;
  casadi_real* w;
} gaitopt_call;

static void gaitopt_close(gaitopt_call* c) {
  free((void*)c->arg); free(c->res); free(c->iw); free(c->w);
}

static int gaitopt_open(gaitopt_call* c, void* f, void* work) {
  casadi_int na = 0, nr = 0, ni = 0, nw = 0;
  c->f = (gaitopt_fn)f;
  c->arg = 0; c->res = 0; c->iw = 0; c->w = 0;
  if (((gaitopt_work_fn)work)(&na, &nr, &ni, &nw)) return 1;
  c->arg = (const casadi_real**)calloc(na > 0 ? na : 1, sizeof(casadi_real*));
  c->res = (casadi_real**)calloc(nr > 0 ? nr : 1, sizeof(casadi_real*));
  c->iw = (casadi_int*)calloc(ni > 0 ? ni : 1, sizeof(casadi_int));
  c->w = (casadi_real*)calloc(nw > 0 ? nw : 1, sizeof(casadi_real));
  if (c->arg && c->res && c->iw && c->w) return 0;
  gaitopt_close(c);
  return 1;
}

/* f(x, u, p) -> out (the phase functions with one output) */
static int gaitopt_xup(gaitopt_call* c, const double* x, const double* u, const double* p,
                       double* out) {
  c->arg[0] = x; c->arg[1] = u; c->arg[2] = p; c->res[0] = out;
  return c->f(c->arg, c->res, c->iw, c->w, 0);
}

typedef struct {
  gaitopt_call step, events, adm, flow, excursion;
  int n, m, n_tr;
  const double *u, *p, *dirs;
  const int* at_end;
  double *ev, *xt, *admv;
  /* the current step's dense output */
  const double *F, *yold;
  double t_old, t_new;
} gaitopt_ctx;

#define GAITOPT_ARM 1e-10       /* phase.py: _ARM */
#define GAITOPT_AT_END 1e-9     /* phase.py: _CONSTRAINT_START */
#define GAITOPT_CHECKS 4        /* kernels/verify.py: CHECKS_PER_STEP */
#define GAITOPT_SAFETY 0.9
#define GAITOPT_MIN_FACTOR 0.2
#define GAITOPT_MAX_FACTOR 10.0
#define GAITOPT_EXPONENT (-0.125) /* -1 / (error estimator order 7 + 1) */

/* Python's min(a, b) and max(a, b): the first unless the second is strictly smaller/larger */
static double gaitopt_min(double a, double b) { return b < a ? b : a; }
static double gaitopt_max(double a, double b) { return b > a ? b : a; }

static double gaitopt_signed(gaitopt_ctx* c, int k, const double* x) {
  gaitopt_xup(&c->events, x, c->u, c->p, c->ev);
  return c->dirs[k] * c->ev[k];
}

/* SciPy's Dop853DenseOutput._call_impl at time tt */
static void gaitopt_dense(gaitopt_ctx* c, double tt, double* out) {
  int i, q, n = c->n;
  double x = (tt - c->t_old) / (c->t_new - c->t_old);
  for (i = 0; i < n; i++) out[i] = 0.0;
  for (q = 0; q < 7; q++) {
    const double* f = c->F + (6 - q) * n;
    double s = (q % 2 == 0) ? x : 1 - x;
    for (i = 0; i < n; i++) out[i] = (out[i] + f[i]) * s;
  }
  for (i = 0; i < n; i++) out[i] += c->yold[i];
}

static double gaitopt_g(gaitopt_ctx* c, int k, double tt) {
  gaitopt_dense(c, tt, c->xt);
  return gaitopt_signed(c, k, c->xt);
}

/* Brent's root bracketing (inverse quadratic interpolation, secant, bisection) of event k on
   the dense output, g(xa) < 0 <= g(xb) */
static double gaitopt_brent(gaitopt_ctx* c, int k, double xa, double xb, double xtol,
                            double rtol, int iterations) {
  double xpre = xa, xcur = xb, xblk = 0.0, fblk = 0.0, spre = 0.0, scur = 0.0;
  double fpre = gaitopt_g(c, k, xpre), fcur = gaitopt_g(c, k, xcur);
  int i;
  if (fpre == 0) return xpre;
  if (fcur == 0) return xcur;
  for (i = 0; i < iterations; i++) {
    double delta, sbis, stry;
    if (fpre != 0 && fcur != 0 && (signbit(fpre) != signbit(fcur))) {
      xblk = xpre; fblk = fpre; spre = scur = xcur - xpre;
    }
    if (fabs(fblk) < fabs(fcur)) { /* keep the best estimate in xcur */
      xpre = xcur; xcur = xblk; xblk = xpre;
      fpre = fcur; fcur = fblk; fblk = fpre;
    }
    delta = (xtol + rtol * fabs(xcur)) / 2;
    sbis = (xblk - xcur) / 2;
    if (fcur == 0 || fabs(sbis) < delta) return xcur;
    if (fabs(spre) > delta && fabs(fcur) < fabs(fpre)) {
      if (xpre == xblk) { /* secant */
        stry = -fcur * (xcur - xpre) / (fcur - fpre);
      } else { /* inverse quadratic */
        double dpre = (fpre - fcur) / (xpre - xcur), dblk = (fblk - fcur) / (xblk - xcur);
        stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre));
      }
      if (2 * fabs(stry) < fmin(fabs(spre), 3 * fabs(sbis) - delta)) {
        spre = scur; scur = stry;
      } else {
        spre = sbis; scur = sbis;
      }
    } else {
      spre = sbis; scur = sbis;
    }
    xpre = xcur; fpre = fcur;
    xcur += fabs(scur) > delta ? scur : (sbis > 0 ? delta : -delta);
    fcur = gaitopt_g(c, k, xcur);
  }
  return xcur;
}

/* phase.py: locate_crossing */
static double gaitopt_locate(gaitopt_ctx* c, int k, double a, double b) {
  double after, t, lo, hi;
  if (!(gaitopt_g(c, k, b) >= 0)) return b;
  after = nextafter(a, INFINITY);
  if (!(gaitopt_g(c, k, a) < 0)) return gaitopt_min(after, b);
  t = gaitopt_brent(c, k, a, b, 1e-15, 4 * DBL_EPSILON, 200);
  if (t > a) return t;
  lo = a; hi = b;
  for (;;) {
    double mid = lo + 0.5 * (hi - lo);
    if (!(lo < mid && mid < hi)) return hi;
    if (gaitopt_g(c, k, mid) >= 0) hi = mid; else lo = mid;
  }
}

/* PhaseFunctions.admissible */
static int gaitopt_admissible(gaitopt_ctx* c, int k, const double* x) {
  if (k >= c->n_tr && c->at_end[k]) {
    gaitopt_xup(&c->events, x, c->u, c->p, c->ev);
    return fabs(c->ev[0]) > GAITOPT_AT_END;
  }
  gaitopt_xup(&c->adm, x, c->u, c->p, c->admv);
  return c->admv[k] > 0;
}

static double gaitopt_rms(const double* v, int n) {
  double s = 0.0;
  int i;
  for (i = 0; i < n; i++) s += v[i] * v[i];
  return sqrt(s) / sqrt((double)n);
}

/* scipy.integrate._ivp.common.select_initial_step (forward, max_step = inf) */
static double gaitopt_initial_step(gaitopt_ctx* c, double t0, double t_bound, const double* y0,
                                   const double* f0, double rtol, double atol, double* work) {
  int i, n = c->n;
  double *scale = work, *v = work + n, *y1 = work + 2 * n, *f1 = work + 3 * n;
  double length = fabs(t_bound - t0), d0, d1, d2, h0, h1, h;
  if (length == 0.0) return 0.0;
  for (i = 0; i < n; i++) scale[i] = atol + fabs(y0[i]) * rtol;
  for (i = 0; i < n; i++) v[i] = y0[i] / scale[i];
  d0 = gaitopt_rms(v, n);
  for (i = 0; i < n; i++) v[i] = f0[i] / scale[i];
  d1 = gaitopt_rms(v, n);
  h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = gaitopt_min(h0, length);
  for (i = 0; i < n; i++) y1[i] = y0[i] + h0 * f0[i];
  gaitopt_xup(&c->flow, y1, c->u, c->p, f1);
  for (i = 0; i < n; i++) v[i] = (f1[i] - f0[i]) / scale[i];
  d2 = gaitopt_rms(v, n) / h0;
  if (d1 <= 1e-15 && d2 <= 1e-15) h1 = gaitopt_max(1e-6, h0 * 1e-3);
  else h1 = pow(0.01 / gaitopt_max(d1, d2), 1.0 / 8.0);
  h = 100 * h0;
  h = gaitopt_min(h, h1);
  h = gaitopt_min(h, length);
  return h;
}

/* One library function f(x, u, p) with one or two outputs (a reset, the guards' rates). */
CASADI_SYMBOL_EXPORT int gaitopt_eval(void* f, void* work, int outputs, const double* x,
                                      const double* u, const double* p, double* out0,
                                      double* out1) {
  gaitopt_call c;
  int code;
  if (gaitopt_open(&c, f, work)) return -1;
  c.arg[0] = x; c.arg[1] = u; c.arg[2] = p; c.res[0] = out0;
  if (outputs > 1) c.res[1] = out1;
  code = c.f(c.arg, c.res, c.iw, c.w, 0);
  gaitopt_close(&c);
  return code;
}

/*
  One arc.  fns: (f, work) pairs of step, events, admissible, flow, excursion.  dims: n, m
  (events), n_tr (transitions).  opts: rtol, atol, t0 (the arc's start), t_bound.
  state (in/out; 4 + 2n + 2m): t, h_abs (< 0: start the arc), max_step, short (0: none),
  y (n), f (n), values (m), armed (m).  Per step taken (at most capacity): stamps[i] (the step's
  end, or the crossing), ends[i] (the step's end), yold (n), F (7n, SciPy's F row by row).
  hit (1 + n): the crossing's time and state; event: its index.
  Returns 0 (a crossing), 1 (t_bound reached), 2 (step too small), 3 (buffers full: call
  again), -1 (a function failed or no memory).
*/
CASADI_SYMBOL_EXPORT int gaitopt_arc(void** fns, const int* dims, const double* u,
                                     const double* p, const double* dirs, const int* at_end,
                                     const double* opts, double* state, int capacity,
                                     double* stamps, double* ends, double* yold, double* F,
                                     int* count, double* hit, int* event) {
  gaitopt_ctx c;
  int n = dims[0], m = dims[1], n_tr = dims[2], i, j, k, code = -1, taken = 0;
  double rtol = opts[0], atol = opts[1], t0 = opts[2], t_bound = opts[3];
  double *t = state, *h_abs_p = state + 1, *max_step = state + 2, *shortb = state + 3;
  double *y = state + 4, *f = y + n, *values = f + n, *armed = values + m;
  double *y_new = 0, *f_new = 0, *Fs = 0, *G = 0, *work = 0, *signed_ = 0, *xh = 0;
  double frac[GAITOPT_CHECKS - 1], tol[2], err = 0.0, hh = 0.0;
  int opened = 0;
  memset(&c, 0, sizeof(c));
  c.n = n; c.m = m; c.n_tr = n_tr; c.u = u; c.p = p; c.dirs = dirs; c.at_end = at_end;
  *count = 0;
  if (gaitopt_open(&c.step, fns[0], fns[1])) goto done;
  opened = 1;
  if (gaitopt_open(&c.events, fns[2], fns[3])) goto done;
  opened = 2;
  if (gaitopt_open(&c.adm, fns[4], fns[5])) goto done;
  opened = 3;
  if (gaitopt_open(&c.flow, fns[6], fns[7])) goto done;
  opened = 4;
  if (gaitopt_open(&c.excursion, fns[8], fns[9])) goto done;
  opened = 5;
  work = (double*)calloc(8 * n + 2 * m + 2 * m * GAITOPT_CHECKS + 2 * n_tr + 8, sizeof(double));
  if (!work) goto done;
  y_new = work + 4 * n; f_new = y_new + n; xh = f_new + n; c.xt = xh + n; c.ev = c.xt + n;
  c.admv = c.ev + m; G = c.admv + m; signed_ = G + m * GAITOPT_CHECKS;
  Fs = (double*)calloc(7 * n, sizeof(double));
  if (!Fs) goto done;
  for (i = 0; i < GAITOPT_CHECKS - 1; i++) frac[i] = (double)(i + 1) / GAITOPT_CHECKS;
  tol[0] = rtol; tol[1] = atol;

  if (*h_abs_p < 0) { /* the arc's start: rate, initial step, arming, excursion bound */
    double bound = INFINITY, *g1 = signed_, *g2 = signed_ + n_tr;
    if (gaitopt_xup(&c.flow, y, u, p, f)) goto done;
    *h_abs_p = gaitopt_initial_step(&c, *t, t_bound, y, f, rtol, atol, work);
    gaitopt_xup(&c.events, y, u, p, c.ev);
    for (k = 0; k < m; k++) {
      values[k] = dirs[k] * c.ev[k];
      armed[k] = values[k] < -GAITOPT_ARM;
    }
    c.excursion.arg[0] = y; c.excursion.arg[1] = u; c.excursion.arg[2] = p;
    c.excursion.res[0] = g1; c.excursion.res[1] = g2;
    if (c.excursion.f(c.excursion.arg, c.excursion.res, c.excursion.iw, c.excursion.w, 0))
      goto done;
    for (k = 0; k < n_tr; k++) /* _short_excursion: tau/4 with tau = 2|g1|/g2, where the */
      if (!armed[k] && g1[k] < 0 && 0 < g2[k] && /* excursion passes half the arming depth */
          values[k] - 0.5 * g1[k] * g1[k] / g2[k] < -0.5 * GAITOPT_ARM)
        bound = gaitopt_min(bound, 0.5 * fabs(g1[k]) / g2[k]);
    *shortb = (isfinite(bound) && bound > 0) ? bound : 0.0;
    *max_step = *shortb > 0 ? *shortb : INFINITY;
  }

  while (taken < capacity) {
    double tt = *t, h_abs = *h_abs_p, t_new = tt, min_step, grid[GAITOPT_CHECKS + 1];
    int rejected = 0, crossing = 0, best = -1, finished;
    double best_t = 0.0;
    /* CompiledDOP853._step_impl */
    min_step = 10 * fabs(nextafter(tt, INFINITY) - tt);
    h_abs = gaitopt_min(gaitopt_max(h_abs, min_step), *max_step);
    for (;;) {
      const double* sarg[7];
      if (h_abs < min_step) { code = 2; goto done; }
      t_new = tt + h_abs;
      if (t_new - t_bound > 0) t_new = t_bound;
      hh = t_new - tt;
      h_abs = fabs(hh);
      sarg[0] = y; sarg[1] = f; sarg[2] = &hh; sarg[3] = frac; sarg[4] = u; sarg[5] = p;
      sarg[6] = tol;
      for (i = 0; i < 7; i++) c.step.arg[i] = sarg[i];
      c.step.res[0] = y_new; c.step.res[1] = f_new; c.step.res[2] = &err; c.step.res[3] = Fs;
      c.step.res[4] = G;
      if (c.step.f(c.step.arg, c.step.res, c.step.iw, c.step.w, 0)) goto done;
      if (err < 1) {
        double factor = err == 0 ? GAITOPT_MAX_FACTOR
                                 : gaitopt_min(GAITOPT_MAX_FACTOR,
                                               GAITOPT_SAFETY * pow(err, GAITOPT_EXPONENT));
        if (rejected) factor = gaitopt_min(1, factor);
        h_abs *= factor;
        break;
      }
      h_abs *= gaitopt_max(GAITOPT_MIN_FACTOR, GAITOPT_SAFETY * pow(err, GAITOPT_EXPONENT));
      rejected = 1;
    }
    /* the step is taken: record its dense output */
    memcpy(yold + (size_t)taken * n, y, n * sizeof(double));
    memcpy(F + (size_t)taken * 7 * n, Fs, 7 * n * sizeof(double));
    ends[taken] = t_new;
    c.F = F + (size_t)taken * 7 * n; c.yold = yold + (size_t)taken * n;
    c.t_old = tt; c.t_new = t_new;
    finished = t_new - t_bound >= 0;
    /* integrate_phase's event logic: the check points, np.linspace(t_old, t_new, CHECKS + 1) */
    for (j = 0; j <= GAITOPT_CHECKS; j++) grid[j] = j * ((t_new - tt) / GAITOPT_CHECKS) + tt;
    grid[GAITOPT_CHECKS] = t_new;
    for (k = 0; k < m; k++)
      for (j = 0; j < GAITOPT_CHECKS; j++) {
        double s = dirs[k] * G[j * m + k];
        double before = j ? signed_[k * GAITOPT_CHECKS + j - 1] : values[k];
        signed_[k * GAITOPT_CHECKS + j] = s;
        if (before < 0 && s >= 0) crossing = 1;
      }
    if (!crossing) {
      for (k = 0; k < m; k++) {
        for (j = 0; j < GAITOPT_CHECKS; j++)
          if (signed_[k * GAITOPT_CHECKS + j] < -GAITOPT_ARM) armed[k] = 1;
        values[k] = signed_[k * GAITOPT_CHECKS + GAITOPT_CHECKS - 1];
      }
    } else {
      for (k = 0; k < m; k++) {
        double previous = values[k];
        int was_armed = armed[k] != 0;
        for (j = 1; j <= GAITOPT_CHECKS; j++) {
          double current = signed_[k * GAITOPT_CHECKS + j - 1];
          if (was_armed && previous < 0 && 0 <= current) { /* confirm on the dense output */
            double a = gaitopt_g(&c, k, grid[j - 1]);
            double b = j < GAITOPT_CHECKS ? gaitopt_g(&c, k, grid[j])
                                          : gaitopt_signed(&c, k, y_new);
            previous = a; current = b;
          }
          if (was_armed && previous < 0 && 0 <= current) {
            double th = gaitopt_locate(&c, k, grid[j - 1], grid[j]);
            gaitopt_dense(&c, th, xh);
            if (gaitopt_admissible(&c, k, xh)) {
              if (best < 0 || th < best_t) {
                best = k; best_t = th;
                hit[0] = th;
                memcpy(hit + 1, xh, n * sizeof(double));
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
    *t = t_new; *h_abs_p = h_abs;
    memcpy(y, y_new, n * sizeof(double));
    memcpy(f, f_new, n * sizeof(double));
    taken++;
    *count = taken;
    if (*shortb > 0) {
      int all = 1;
      for (k = 0; k < n_tr; k++) all = all && armed[k] != 0;
      if (all || t_new - t0 > 8 * *shortb) { *max_step = INFINITY; *shortb = 0.0; }
    }
    if (best >= 0) {
      stamps[taken - 1] = best_t;
      *event = best;
      code = 0;
      goto done;
    }
    stamps[taken - 1] = t_new;
    if (finished) { code = 1; goto done; }
  }
  code = 3;
done:
  free(work); free(Fs);
  if (opened > 0) gaitopt_close(&c.step);
  if (opened > 1) gaitopt_close(&c.events);
  if (opened > 2) gaitopt_close(&c.adm);
  if (opened > 3) gaitopt_close(&c.flow);
  if (opened > 4) gaitopt_close(&c.excursion);
  return code;
}
"""
