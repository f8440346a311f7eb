"""The C source of the compiled shooting Newton (:mod:`gaitopt.kernels.newton`).

One library for every model class and mesh: it calls a model's compiled kernels
(:mod:`gaitopt.kernels.symbolic`: ``lift``, per phase ``fold_i``, ``end_i``, the residual's
``step_i`` and, where the phase has one, ``foldx_i``) through their addresses, as the arc
driver does (:mod:`gaitopt.kernels.arc_driver`), so nothing of a model is compiled twice and the
mesh (segments, RK steps per segment, period) is an argument.  It holds

* ``gaitopt_newton_eval`` — the shooting residual and (with ``jac``) its Jacobians ``∂F/∂w``,
  ``∂F/∂u``, ``∂F/∂p``, the return state, the phase ends, guard rates and admissibility: the
  arithmetic of :meth:`gaitopt.kernels.assemble.Assembly._assemble` block for block (each segment
  ``N`` folds from ``D = [I, 0]``; the gaps, the guard, the reset link, periodicity);
* ``gaitopt_newton_solve`` — plain Newton on it, the loop of :func:`gaitopt.orbit.newton.newton`
  (same stopping tests in the same order: a non-finite ``F`` or ``∂F/∂w`` stops, ``max |F| ≤
  abstol`` converges, else the step by an LU with partial pivoting (LAPACK ``getrf``'s pivot
  choice: the first entry of largest modulus), ``max |step| ≤ abstol_step`` converges at the
  point before the step, else ``w ← w − step``), leaving the evaluation at the last point.  Its
  iterations evaluate ``∂F/∂w`` alone (``jac`` 2: the phases with a ``foldx_i`` carry only the
  segment start's and duration's derivatives, the kneed walker's first phase 7 columns instead
  of 20); at the point it returns the full evaluation is made once (``∂F/∂u``, ``∂F/∂p`` for the
  return map; ``∂F/∂w`` the same to the bit);
* ``gaitopt_newton_map`` — the return map's Jacobians at that point by block elimination of the
  same Jacobian (eq. (1) of :mod:`gaitopt.orbit.sensitivity`: ``A = P_s − P_z G_z⁻¹ G_s``,
  ``B_u``, ``B_p`` likewise, ``G_z`` factored once);
* ``gaitopt_newton_samples`` — the dense samples: each segment's states after each of ``N`` RK
  steps without derivatives (``step_i``; :func:`gaitopt.kernels.trajectory_function`'s);
* ``gaitopt_newton_correct`` — the error estimate's step ``−(∂F/∂w)⁻¹ F_fine`` with ``F_fine``
  the residual on a mesh with more RK steps (:meth:`ShootingTranscription.correction`).

Kernel outputs may be sparse (CasADi's compressed-column nonzeros): each output's nonzeros are
scattered to a dense column-major block by an index list made in Python.
"""

__all__ = ["SOURCE"]

SOURCE = r"""
/* ---- gaitopt shooting Newton (gaitopt/kernels/newton_driver.py) -------------------------- */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#define casadi_real double
#define casadi_int long long int
#define CASADI_SYMBOL_EXPORT

typedef int (*gn_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);
typedef int (*gn_work_fn)(casadi_int*, casadi_int*, casadi_int*, casadi_int*);

/* one kernel: its buffers and how its outputs are scattered */
typedef struct {
  gn_fn f;
  const casadi_real** arg;
  casadi_real** res;
  casadi_int* iw;
  casadi_real* w;
  int n_out;
  const int* nnz;    /* per output: nonzeros */
  const int* numel;  /* per output: rows x cols */
  const int** idx;   /* per output: dense column-major index of each nonzero; 0: dense */
  double* nz;        /* the sparse outputs' nonzeros */
} gn_call;

static void gn_close(gn_call* c) {
  free((void*)c->arg); free(c->res); free(c->iw); free(c->w); free((void*)c->idx); free(c->nz);
  c->arg = 0; c->res = 0; c->iw = 0; c->w = 0; c->idx = 0; c->nz = 0;
}

/* spec: n_out, then per output (nnz, numel, dense), then the sparse outputs' indices */
static int gn_open(gn_call* c, void* f, void* work, const int* spec) {
  casadi_int na = 0, nr = 0, ni = 0, nw = 0;
  int j, total = 0;
  const int* at;
  memset(c, 0, sizeof(*c));
  c->f = (gn_fn)f;
  if (!f || ((gn_work_fn)work)(&na, &nr, &ni, &nw)) return 1;
  c->n_out = spec[0];
  c->nnz = spec + 1;  /* stride 3 */
  c->arg = (const casadi_real**)calloc(na > 0 ? na : 1, sizeof(casadi_real*));
  c->res = (casadi_real**)calloc(nr > 0 ? nr : 1, sizeof(casadi_real*));
  c->iw = (casadi_int*)calloc(ni > 0 ? ni : 1, sizeof(casadi_int));
  c->w = (casadi_real*)calloc(nw > 0 ? nw : 1, sizeof(casadi_real));
  c->idx = (const int**)calloc(c->n_out > 0 ? c->n_out : 1, sizeof(int*));
  at = spec + 1 + 3 * c->n_out;
  for (j = 0; j < c->n_out; j++) {
    if (!spec[3 + 3 * j]) { c->idx[j] = at; at += spec[1 + 3 * j]; total += spec[1 + 3 * j]; }
  }
  c->nz = (double*)calloc(total > 0 ? total : 1, sizeof(double));
  if (c->arg && c->res && c->iw && c->w && c->idx && c->nz) return 0;
  gn_close(c);
  return 1;
}

/* outs[j]: a dense column-major block (or 0: not wanted) */
static int gn_run(gn_call* c, const double** args, int n_args, double** outs) {
  int j, k, code;
  double* nz = c->nz;
  for (j = 0; j < n_args; j++) c->arg[j] = args[j];
  for (j = 0; j < c->n_out; j++) {
    if (!outs[j]) { c->res[j] = 0; continue; }
    if (c->idx[j]) { c->res[j] = nz; nz += c->nnz[3 * j]; } else c->res[j] = outs[j];
  }
  code = c->f(c->arg, c->res, c->iw, c->w, 0);
  if (code) return code;
  for (j = 0; j < c->n_out; j++) {
    if (outs[j] && c->idx[j]) {
      const double* v = c->res[j];
      memset(outs[j], 0, sizeof(double) * c->nnz[3 * j + 1]);
      for (k = 0; k < c->nnz[3 * j]; k++) outs[j][c->idx[j][k]] = v[k];
    }
  }
  return 0;
}

typedef struct {
  int K, S, m, size, nu, np, n_g, max_n, nr_last;
  int *n, *off, *offT, *sec, *ng, *nr;
  gn_call lift;
  gn_call *fold, *end, *step, *foldx;
  int have_step, have_foldx;
  int* hasx;  /* per chain element: 1 where it has a foldx */
  /* outputs (owned by the caller): F, J (row-major size x size), Ju, Jp, x_return, ends, rates,
     admissible */
  double *F, *J, *Ju, *Jp, *xret, *ends, *rates, *adm;
  /* scratch */
  double *xl, *Ls, *Lp, *xa, *xb, *Da, *Db, *Xend, *Ds, *E, *Ep, *Eu;
  double *g, *gx, *gu, *gp, *r, *rx, *ru, *rp, *Dzero;
  double *lu, *step_v, *Z, *scratch;
  int* piv;
} gn_problem;

/* dims: K, S, m, size, nu, np, then per chain element n, off, offT; then sec (m) */
CASADI_SYMBOL_EXPORT void gaitopt_newton_close(gn_problem* h) {
  int k;
  if (!h) return;
  gn_close(&h->lift);
  for (k = 0; k < h->K; k++) {
    if (h->fold) gn_close(&h->fold[k]);
    if (h->end) gn_close(&h->end[k]);
    if (h->step) gn_close(&h->step[k]);
    if (h->foldx) gn_close(&h->foldx[k]);
  }
  free(h->fold); free(h->end); free(h->step); free(h->foldx); free(h->n); free(h->xl);
  free(h->lu); free(h->piv); free(h->Z); free(h->scratch);
  free(h);
}

/* fns: lift (f, work), then per chain element fold, end, step, foldx (f, work; step and foldx
   may be 0, 0).
   specs: the same functions' output specs (see gn_open).  outs: F, J, Ju, Jp, x_return, ends,
   rates, admissible (the caller's arrays). */
CASADI_SYMBOL_EXPORT gn_problem* gaitopt_newton_open(const int* dims, void** fns,
                                                      const int** specs, double** outs) {
  gn_problem* h = (gn_problem*)calloc(1, sizeof(gn_problem));
  int k, K, q, total, max_n = 0, max_g = 1, max_r = 1;
  if (!h) return 0;
  K = h->K = dims[0]; h->S = dims[1]; h->m = dims[2]; h->size = dims[3];
  h->nu = dims[4]; h->np = dims[5];
  h->n = (int*)calloc(8 * K + h->m + 1, sizeof(int));
  h->fold = (gn_call*)calloc(K, sizeof(gn_call));
  h->end = (gn_call*)calloc(K, sizeof(gn_call));
  h->step = (gn_call*)calloc(K, sizeof(gn_call));
  h->foldx = (gn_call*)calloc(K, sizeof(gn_call));
  if (!h->n || !h->fold || !h->end || !h->step || !h->foldx) {
    gaitopt_newton_close(h); return 0;
  }
  h->off = h->n + K; h->offT = h->n + 2 * K; h->ng = h->n + 3 * K; h->nr = h->n + 4 * K;
  h->sec = h->n + 7 * K; h->hasx = h->n + 7 * K + h->m;
  for (k = 0; k < K; k++) {
    h->n[k] = dims[6 + 3 * k]; h->off[k] = dims[7 + 3 * k]; h->offT[k] = dims[8 + 3 * k];
    if (h->n[k] > max_n) max_n = h->n[k];
  }
  for (k = 0; k < h->m; k++) h->sec[k] = dims[6 + 3 * K + k];
  h->max_n = max_n;
  if (gn_open(&h->lift, fns[0], fns[1], specs[0])) { gaitopt_newton_close(h); return 0; }
  h->have_step = 1;
  h->have_foldx = 0;
  for (k = 0; k < K; k++) {
    if (gn_open(&h->fold[k], fns[2 + 8 * k], fns[3 + 8 * k], specs[1 + 4 * k]) ||
        gn_open(&h->end[k], fns[4 + 8 * k], fns[5 + 8 * k], specs[2 + 4 * k])) {
      gaitopt_newton_close(h); return 0;
    }
    if (!fns[6 + 8 * k] || gn_open(&h->step[k], fns[6 + 8 * k], fns[7 + 8 * k],
                                   specs[3 + 4 * k]))
      h->have_step = 0;
    h->hasx[k] = fns[8 + 8 * k] && !gn_open(&h->foldx[k], fns[8 + 8 * k], fns[9 + 8 * k],
                                             specs[4 + 4 * k]);
    if (h->hasx[k]) h->have_foldx = 1;
    h->ng[k] = h->end[k].nnz[3 * 0 + 1];  /* numel of g */
    h->nr[k] = h->end[k].nnz[3 * 4 + 1];  /* numel of r */
    if (h->ng[k] > max_g) max_g = h->ng[k];
    if (h->nr[k] > max_r) max_r = h->nr[k];
  }
  h->nr_last = h->nr[K - 1];
  h->F = outs[0]; h->J = outs[1]; h->Ju = outs[2]; h->Jp = outs[3]; h->xret = outs[4];
  h->ends = outs[5]; h->rates = outs[6]; h->adm = outs[7];
  q = max_n + h->nu + h->np + 1;
  total = max_n + max_n * h->m + max_n * h->np      /* xl, Ls, Lp */
        + 2 * max_n + 2 * max_n * q                /* xa, xb, Da, Db */
        + max_n * h->S + h->S * max_n * q          /* Xend, Ds */
        + max_n * h->size + max_n * h->np + max_n * h->nu  /* E, Ep, Eu */
        + max_g * (1 + max_n + h->nu + h->np)      /* g, gx, gu, gp */
        + max_r * (1 + max_n + h->nu + h->np)      /* r, rx, ru, rp */
        + max_n * q;                               /* Dzero */
  h->xl = (double*)calloc(total, sizeof(double));
  h->lu = (double*)calloc(h->size * h->size + h->size, sizeof(double));
  h->piv = (int*)calloc(h->size + 1, sizeof(int));
  h->Z = (double*)calloc(h->size * (h->m + h->nu + h->np) + 1, sizeof(double));
  for (total = 0, k = 0; k < K; k++) total += h->n[k];
  h->scratch = (double*)calloc(total + 2 * K + max_r, sizeof(double));  /* ends, rates, adm, r */
  if (!h->xl || !h->lu || !h->piv || !h->Z || !h->scratch) {
    gaitopt_newton_close(h); return 0;
  }
  h->Ls = h->xl + max_n; h->Lp = h->Ls + max_n * h->m; h->xa = h->Lp + max_n * h->np;
  h->xb = h->xa + max_n; h->Da = h->xb + max_n; h->Db = h->Da + max_n * q;
  h->Xend = h->Db + max_n * q; h->Ds = h->Xend + max_n * h->S;
  h->E = h->Ds + h->S * max_n * q; h->Ep = h->E + max_n * h->size; h->Eu = h->Ep + max_n * h->np;
  h->g = h->Eu + max_n * h->nu; h->gx = h->g + max_g; h->gu = h->gx + max_g * max_n;
  h->gp = h->gu + max_g * h->nu; h->r = h->gp + max_g * h->np; h->rx = h->r + max_r;
  h->ru = h->rx + max_r * max_n; h->rp = h->ru + max_r * h->nu; h->Dzero = h->rp + max_r * h->np;
  h->step_v = h->lu + h->size * h->size;
  return h;
}

/* the start of segment j of chain element k (0: the lift) */
static const double* gn_start(gn_problem* h, const double* w, int k, int j) {
  int n = h->n[k];
  if (k == 0) return j == 0 ? h->xl : w + h->off[k] + n * (j - 1);
  return w + h->off[k] + n * j;
}

/* the column of w where segment start j's block begins, -1: the lift */
static int gn_col(gn_problem* h, int k, int j) {
  if (k == 0) return j == 0 ? -1 : h->off[k] + h->n[k] * (j - 1);
  return h->off[k] + h->n[k] * j;
}

/* rows R..R+n of J (and Jp) += sign * M * d(segment start j)/d(w, p); M = D[:, :n] (column-major,
   n rows) or the identity (D = 0) */
static void gn_add_state(gn_problem* h, int k, int R, int j, const double* D, double sign) {
  int n = h->n[k], size = h->size, m = h->m, np = h->np, i, l, a;
  int c = gn_col(h, k, j);
  for (i = 0; i < n; i++) {
    double* Jrow = h->J + (R + i) * size;
    if (c < 0) {
      for (l = 0; l < m; l++) {
        double s = 0;
        if (D) for (a = 0; a < n; a++) s += D[i + n * a] * h->Ls[a + n * l];
        else s = h->Ls[i + n * l];
        Jrow[l] += sign * s;
      }
      for (l = 0; l < np; l++) {
        double s = 0;
        if (D) for (a = 0; a < n; a++) s += D[i + n * a] * h->Lp[a + n * l];
        else s = h->Lp[i + n * l];
        h->Jp[(R + i) * np + l] += sign * s;
      }
    } else if (D) {
      for (l = 0; l < n; l++) Jrow[c + l] += sign * D[i + n * l];
    } else {
      Jrow[c + i] += sign;
    }
  }
}

/* The shooting equations at w with N RK steps per segment (see the module docstring); jac: 1
   with the Jacobians, 0 the residual alone, 2 with dF/dw alone (Newton's iterations: the
   segments of the chain elements with a foldx carry only their derivatives with respect to the
   segment start and the duration; Ju and Jp are then incomplete). */
CASADI_SYMBOL_EXPORT int gaitopt_newton_eval(gn_problem* h, const double* w, const double* u,
                                             const double* p, int N, int jac) {
  int K = h->K, S = h->S, m = h->m, size = h->size, nu = h->nu, np = h->np;
  int k, j, i, l, a, t, row = 0, at_end = 0, code, folds;
  double Nd = (double)N;
  const double* args[6];
  double* outs[10];
  folds = jac || !h->have_step;  /* the residual alone by the folds where there are no steps */
  args[0] = w; args[1] = p;
  outs[0] = h->xl; outs[1] = jac ? h->Ls : 0; outs[2] = jac ? h->Lp : 0;
  if ((code = gn_run(&h->lift, args, 2, outs))) return code;
  if (jac) {
    memset(h->J, 0, sizeof(double) * size * size);
    memset(h->Ju, 0, sizeof(double) * size * nu);
    memset(h->Jp, 0, sizeof(double) * size * np);
  }
  for (k = 0; k < K; k++) {
    int n = h->n[k], ng = h->ng[k], nr = h->nr[k], offT = h->offT[k], c;
    int reduced = jac == 2 && h->hasx[k];
    int q = reduced ? n + 1 : n + nu + np + 1;  /* D's columns: [x0; u; p; hs] or [x0; hs] */
    int nup = reduced ? 0 : 1;                   /* D has the u and p columns */
    gn_call* fold = reduced ? &h->foldx[k] : &h->fold[k];
    double T = w[offT], hs = T / S;
    const double* Dl;
    const double* x_end;
    /* -- the segments: N RK steps each, with their derivatives D = dx/d[x0; u; p; hs] -- */
    for (j = 0; j < S; j++) {
      double *x = h->xa, *D = h->Da, *xn = h->xb, *Dn = h->Db, *swap;
      memcpy(x, gn_start(h, w, k, j), sizeof(double) * n);
      if (folds) {
        memset(D, 0, sizeof(double) * n * q);
        if (jac) for (i = 0; i < n; i++) D[i + n * i] = 1.0;
      }
      for (t = 0; t < N; t++) {
        args[0] = x; outs[0] = xn;
        if (folds) {
          args[1] = D; args[2] = u; args[3] = p; args[4] = &hs; args[5] = &Nd;
          outs[1] = Dn;
          code = gn_run(fold, args, 6, outs);
          swap = D; D = Dn; Dn = swap;
        } else {
          args[1] = u; args[2] = p; args[3] = &hs; args[4] = &Nd;
          code = gn_run(&h->step[k], args, 5, outs);
        }
        if (code) return code;
        swap = x; x = xn; xn = swap;
      }
      memcpy(h->Xend + n * j, x, sizeof(double) * n);
      if (jac) memcpy(h->Ds + j * n * q, D, sizeof(double) * n * q);
    }
    /* -- close the gaps -- */
    for (j = 0; j + 1 < S; j++) {
      const double* next = gn_start(h, w, k, j + 1);
      int R = row + j * n;
      for (i = 0; i < n; i++) h->F[R + i] = next[i] - h->Xend[n * j + i];
      if (jac) {
        const double* D = h->Ds + j * n * q;
        gn_add_state(h, k, R, j + 1, 0, 1.0);
        gn_add_state(h, k, R, j, D, -1.0);
        for (i = 0; i < n; i++) {
          h->J[(R + i) * size + offT] -= D[i + n * (q - 1)] / S;
          if (!nup) continue;
          for (l = 0; l < nu; l++) h->Ju[(R + i) * nu + l] -= D[i + n * (n + l)];
          for (l = 0; l < np; l++) h->Jp[(R + i) * np + l] -= D[i + n * (n + nu + l)];
        }
      }
    }
    row += n * (S - 1);
    /* -- the end state's derivative E = dx_end/dw (rows n), E_p, E_u -- */
    x_end = h->Xend + n * (S - 1);
    memcpy(h->ends + at_end, x_end, sizeof(double) * n);
    at_end += n;
    if (jac) {
      Dl = h->Ds + (S - 1) * n * q;
      memset(h->E, 0, sizeof(double) * n * size);
      for (i = 0; i < n; i++) {
        for (l = 0; l < np; l++) h->Ep[i * np + l] = nup ? Dl[i + n * (n + nu + l)] : 0.0;
        for (l = 0; l < nu; l++) h->Eu[i * nu + l] = nup ? Dl[i + n * (n + l)] : 0.0;
      }
      c = gn_col(h, k, S - 1);
      for (i = 0; i < n; i++) {
        if (c < 0) {
          for (l = 0; l < m; l++) {
            double s = 0;
            for (a = 0; a < n; a++) s += Dl[i + n * a] * h->Ls[a + n * l];
            h->E[i * size + l] = s;
          }
          for (l = 0; l < np; l++) {
            double s = 0;
            for (a = 0; a < n; a++) s += Dl[i + n * a] * h->Lp[a + n * l];
            h->Ep[i * np + l] += s;
          }
        } else {
          for (l = 0; l < n; l++) h->E[i * size + c + l] = Dl[i + n * l];
        }
        h->E[i * size + offT] += Dl[i + n * (q - 1)] / S;
      }
    }
    /* -- the transition: guard, reset (and their Jacobians), rate, admissibility -- */
    args[0] = x_end; args[1] = u; args[2] = p;
    outs[0] = h->g; outs[1] = jac ? h->gx : 0; outs[2] = jac ? h->gu : 0;
    outs[3] = jac ? h->gp : 0; outs[4] = h->r; outs[5] = jac ? h->rx : 0;
    outs[6] = jac ? h->ru : 0; outs[7] = jac ? h->rp : 0; outs[8] = h->rates + k;
    outs[9] = h->adm + k;
    if ((code = gn_run(&h->end[k], args, 3, outs))) return code;
    for (a = 0; a < ng; a++) {
      int R = row + a;
      h->F[R] = h->g[a];
      if (!jac) continue;
      for (l = 0; l < size; l++) {
        double s = 0;
        for (i = 0; i < n; i++) s += h->gx[a + ng * i] * h->E[i * size + l];
        h->J[R * size + l] += s;
      }
      for (l = 0; l < nu; l++) {
        double s = h->gu[a + ng * l];
        for (i = 0; i < n; i++) s += h->gx[a + ng * i] * h->Eu[i * nu + l];
        h->Ju[R * nu + l] += s;
      }
      for (l = 0; l < np; l++) {
        double s = h->gp[a + ng * l];
        for (i = 0; i < n; i++) s += h->gx[a + ng * i] * h->Ep[i * np + l];
        h->Jp[R * np + l] += s;
      }
    }
    row += ng;
    if (k + 1 < K) {  /* the reset links to the next phase: x_next - r = 0 */
      int off1 = h->off[k + 1];
      for (a = 0; a < nr; a++) {
        int R = row + a;
        h->F[R] = w[off1 + a] - h->r[a];
        if (!jac) continue;
        h->J[R * size + off1 + a] += 1.0;
        for (l = 0; l < size; l++) {
          double s = 0;
          for (i = 0; i < n; i++) s += h->rx[a + nr * i] * h->E[i * size + l];
          h->J[R * size + l] -= s;
        }
        for (l = 0; l < nu; l++) {
          double s = h->ru[a + nr * l];
          for (i = 0; i < n; i++) s += h->rx[a + nr * i] * h->Eu[i * nu + l];
          h->Ju[R * nu + l] -= s;
        }
        for (l = 0; l < np; l++) {
          double s = h->rp[a + nr * l];
          for (i = 0; i < n; i++) s += h->rx[a + nr * i] * h->Ep[i * np + l];
          h->Jp[R * np + l] -= s;
        }
      }
      row += nr;
    } else {  /* periodicity: r[section] - s = 0 */
      memcpy(h->xret, h->r, sizeof(double) * nr);
      for (a = 0; a < m; a++) {
        int R = row + a, b = h->sec[a];
        h->F[R] = h->r[b] - w[a];
        if (!jac) continue;
        for (l = 0; l < size; l++) {
          double s = 0;
          for (i = 0; i < n; i++) s += h->rx[b + nr * i] * h->E[i * size + l];
          h->J[R * size + l] += s;
        }
        h->J[R * size + a] -= 1.0;
        for (l = 0; l < nu; l++) {
          double s = h->ru[b + nr * l];
          for (i = 0; i < n; i++) s += h->rx[b + nr * i] * h->Eu[i * nu + l];
          h->Ju[R * nu + l] += s;
        }
        for (l = 0; l < np; l++) {
          double s = h->rp[b + nr * l];
          for (i = 0; i < n; i++) s += h->rx[b + nr * i] * h->Ep[i * np + l];
          h->Jp[R * np + l] += s;
        }
      }
      row += m;
    }
  }
  return row == size ? 0 : -4;
}

/* The dense samples: per chain element, the state at the start of each segment and after each
   of its N RK steps (without derivatives), n x S (N + 1) column-major, the elements one after
   the other in out (trajectory_function's samples). */
CASADI_SYMBOL_EXPORT int gaitopt_newton_samples(gn_problem* h, const double* w, const double* u,
                                                const double* p, int N, double* out) {
  int K = h->K, S = h->S, nu = h->nu, np = h->np, k, j, t, code;
  double Nd = (double)N;
  const double* args[6];
  double* outs[3];
  args[0] = w; args[1] = p;
  outs[0] = h->xl; outs[1] = 0; outs[2] = 0;
  if ((code = gn_run(&h->lift, args, 2, outs))) return code;
  for (k = 0; k < K; k++) {
    int n = h->n[k], q = n + nu + np + 1;
    double hs = w[h->offT[k]] / S;
    if (!h->have_step) memset(h->Da, 0, sizeof(double) * n * q);
    for (j = 0; j < S; j++) {
      memcpy(out, gn_start(h, w, k, j), sizeof(double) * n);
      for (t = 0; t < N; t++) {
        args[0] = out; outs[0] = out + n;
        if (h->have_step) {
          args[1] = u; args[2] = p; args[3] = &hs; args[4] = &Nd;
          code = gn_run(&h->step[k], args, 5, outs);
        } else {  /* the fold with D = 0 (its derivatives not wanted) */
          args[1] = h->Da; args[2] = u; args[3] = p; args[4] = &hs; args[5] = &Nd;
          outs[1] = h->Db;
          code = gn_run(&h->fold[k], args, 6, outs);
        }
        if (code) return code;
        out += n;
      }
      out += n;
    }
  }
  return 0;
}

/* LU with partial pivoting of the n x n row-major A in place (getrf's pivot: the first entry
   of largest modulus); 1 where a pivot is exactly zero */
static int gn_lu(double* A, int* piv, int n) {
  int i, j, k;
  for (k = 0; k < n; k++) {
    int best = k;
    double big = fabs(A[k * n + k]);
    for (i = k + 1; i < n; i++) {
      double v = fabs(A[i * n + k]);
      if (v > big) { big = v; best = i; }
    }
    piv[k] = best;
    if (A[best * n + k] == 0.0) return 1;
    if (best != k)
      for (j = 0; j < n; j++) {
        double t = A[k * n + j];
        A[k * n + j] = A[best * n + j];
        A[best * n + j] = t;
      }
    for (i = k + 1; i < n; i++) {
      double f = (A[i * n + k] /= A[k * n + k]);
      if (f != 0.0)
        for (j = k + 1; j < n; j++) A[i * n + j] -= f * A[k * n + j];
    }
  }
  return 0;
}

/* solve with gn_lu's factors: b (n) in place */
static void gn_lu_solve(const double* A, const int* piv, int n, double* b) {
  int i, j;
  for (i = 0; i < n; i++) if (piv[i] != i) { double t = b[i]; b[i] = b[piv[i]]; b[piv[i]] = t; }
  for (i = 0; i < n; i++) for (j = 0; j < i; j++) b[i] -= A[i * n + j] * b[j];
  for (i = n - 1; i >= 0; i--) {
    for (j = i + 1; j < n; j++) b[i] -= A[i * n + j] * b[j];
    b[i] /= A[i * n + i];
  }
}

static int gn_finite(const double* v, int n) {
  int i;
  for (i = 0; i < n; i++) if (!isfinite(v[i])) return 0;
  return 1;
}

static double gn_max_abs(const double* v, int n) {
  int i;
  double s = 0;
  for (i = 0; i < n; i++) if (fabs(v[i]) > s) s = fabs(v[i]);
  return s;
}

/* Plain Newton from w (in/out).  info: [iterations, max |F| at w].  Returns 1 (max |F| <=
   abstol), 2 (max |step| <= abstol_step), 0 (max_iter iterations), -1 (F or dF/dw not finite),
   -2 (dF/dw exactly singular: the caller's least squares), other: a kernel failed.  The
   evaluation (F, J, ...) is left at the returned w. */
static int gn_full(gn_problem* h, const double* w, const double* u, const double* p, int N,
                   int result) {
  int code;
  if (!h->have_foldx) return result;
  if ((code = gaitopt_newton_eval(h, w, u, p, N, 1))) return code > 0 ? 100 + code : code - 100;
  return result;
}

CASADI_SYMBOL_EXPORT int gaitopt_newton_solve(gn_problem* h, double* w, const double* u,
                                              const double* p, int N, int max_iter,
                                              double abstol, double abstol_step, double* info) {
  int it, i, code, size = h->size, mode = h->have_foldx ? 2 : 1;
  /* The iterations need dF/dw alone (mode 2: the foldx kernels); at the point returned the
     full evaluation (the fold kernels: dF/du, dF/dp for the return map, and dF/dw as without
     foldx) is made once. */
  for (it = 1; it <= max_iter; it++) {
    if ((code = gaitopt_newton_eval(h, w, u, p, N, mode)))
      return code > 0 ? 100 + code : code - 100;
    info[0] = it;
    info[1] = gn_max_abs(h->F, size);
    if (!gn_finite(h->F, size) || !gn_finite(h->J, size * size)) return gn_full(h, w, u, p, N, -1);
    if (info[1] <= abstol) return gn_full(h, w, u, p, N, 1);
    memcpy(h->lu, h->J, sizeof(double) * size * size);
    if (gn_lu(h->lu, h->piv, size)) return -2;
    memcpy(h->step_v, h->F, sizeof(double) * size);
    gn_lu_solve(h->lu, h->piv, size, h->step_v);
    if (gn_max_abs(h->step_v, size) <= abstol_step) return gn_full(h, w, u, p, N, 2);
    for (i = 0; i < size; i++) w[i] -= h->step_v[i];
  }
  if ((code = gaitopt_newton_eval(h, w, u, p, N, 1))) return code > 0 ? 100 + code : code - 100;
  info[0] = max_iter;
  info[1] = gn_max_abs(h->F, size);
  return 0;
}

/* Eq. (1) of gaitopt/orbit/sensitivity.py on the current Jacobian: A = P_s - P_z G_z^-1 G_s (m x
   m), B_u = P_u - P_z G_z^-1 G_u (m x nu), B_p likewise (m x np), row-major; G the first
   n_g = size - m rows, P the periodicity rows with s added back (F = [G; P - s]).  Returns 0, or
   1 where G_z is exactly singular. */
CASADI_SYMBOL_EXPORT int gaitopt_newton_map(gn_problem* h, double* A, double* Bu, double* Bp) {
  int size = h->size, m = h->m, nu = h->nu, np = h->np, ng = size - m, cols = m + nu + np;
  int i, j, l;
  double* Gz = h->lu;              /* ng x ng */
  double* Z = h->Z;                /* ng x cols: G_z^-1 [G_s, G_u, G_p] */
  double* col = h->step_v;
  for (i = 0; i < ng; i++)
    for (j = 0; j < ng; j++) Gz[i * ng + j] = h->J[i * size + m + j];
  if (ng && gn_lu(Gz, h->piv, ng)) return 1;
  for (l = 0; l < cols; l++) {
    for (i = 0; i < ng; i++)
      col[i] = l < m ? h->J[i * size + l]
             : l < m + nu ? h->Ju[i * nu + l - m] : h->Jp[i * np + l - m - nu];
    if (ng) gn_lu_solve(Gz, h->piv, ng, col);
    for (i = 0; i < ng; i++) Z[i * cols + l] = col[i];
  }
  for (i = 0; i < m; i++) {
    int R = ng + i;
    for (l = 0; l < cols; l++) {
      double s = l < m ? h->J[R * size + l] + (l == i ? 1.0 : 0.0)
               : l < m + nu ? h->Ju[R * nu + l - m] : h->Jp[R * np + l - m - nu];
      for (j = 0; j < ng; j++) s -= h->J[R * size + m + j] * Z[j * cols + l];
      if (l < m) A[i * m + l] = s;
      else if (l < m + nu) Bu[i * nu + l - m] = s;
      else Bp[i * np + l - m - nu] = s;
    }
  }
  return 0;
}

/* The error estimate's Newton correction at w: -J^-1 F_fine, F_fine the residual with
   N_fine RK steps per segment, J the current Jacobian (kept: the fine residual is written to
   out, not to F).  Returns 0, 1 where J is exactly singular, else a kernel failure. */
CASADI_SYMBOL_EXPORT int gaitopt_newton_correct(gn_problem* h, const double* w, const double* u,
                                                const double* p, int N_fine, double* out) {
  int size = h->size, i, code;
  double* keep = h->F;
  double* keep_ends = h->ends;
  double* keep_rates = h->rates;
  double* keep_adm = h->adm;
  double* keep_ret = h->xret;
  int ends = 0, k;
  memcpy(h->lu, h->J, sizeof(double) * size * size);
  if (gn_lu(h->lu, h->piv, size)) return 1;
  for (k = 0; k < h->K; k++) ends += h->n[k];
  h->F = out;  /* the fine mesh's ends, rates, admissibility, return state: not kept */
  h->ends = h->scratch; h->rates = h->scratch + ends; h->adm = h->rates + h->K;
  h->xret = h->adm + h->K;
  code = gaitopt_newton_eval(h, w, u, p, N_fine, 0);
  h->F = keep; h->ends = keep_ends; h->rates = keep_rates; h->adm = keep_adm; h->xret = keep_ret;
  if (code) return code > 0 ? 100 + code : code - 100;
  gn_lu_solve(h->lu, h->piv, size, out);
  for (i = 0; i < size; i++) out[i] = -out[i];
  return 0;
}
"""
