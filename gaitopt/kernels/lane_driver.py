"""The C source of the lane driver ``gaitopt_lanes``: the batch of ``gaitopt_batch``
(:mod:`gaitopt.kernels.batch_driver`) with :data:`~gaitopt.kernels.vector_step.LANES` starts in
flight, their step tries made by one call of the model's vector step
(:mod:`gaitopt.kernels.vector_step`).

Each lane is one start with its own time, step size, phase, step count, event state and event
record; the driver is ``gaitopt_batch``'s loop over starts and ``gaitopt_arc``'s loop over steps
turned inside out into a state machine per lane (:mod:`gaitopt.kernels.lane_state`; this module
adds the rounds, ``gaitopt_lanes``):

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
step's bits (with its exact math), so every start ends as in ``gaitopt_batch`` to the bit
(tested, ``tests/test_simulation_batch_lanes.py``).  Per-start inputs and parameters: ``u_stride``
(``dims[5]``) and ``p_stride`` (``dims[8]``; 0: one parameter vector for all starts) as in
``gaitopt_batch``.
"""

from __future__ import annotations

from .lane_state import LANE_STATE

__all__ = ["LANES_SOURCE"]


_SOURCE = r"""
/* ---- gaitopt lane driver (gaitopt/kernels/lane_driver.py) ------------------------------ */
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
LANES_SOURCE = LANE_STATE + _SOURCE
