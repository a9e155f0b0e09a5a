"""A live IDAS integrator for :meth:`FluxModel.step`: kept between calls, restarted only
when an input jumps.

CasADi's integrator sets IDAS up and restarts it (order 1, tiny first steps, a consistent
initialisation) on every call: on TR09 at 1 ms calls that was 96-97 % of
:meth:`~maglevkit.models.flux.FluxModel.step`.  Here the flux model's own residual,
Jacobian, quadrature, balance and output functions (the same CasADi expressions as the
integrator's, generated to C) drive SUNDIALS IDAS directly, from the IDAS that CasADi ships
(its ``libcasadi_integrator_idas``): one IDAS memory per model, re-initialised (with a
consistent initial condition, as CasADi does) only where the voltages, the step length or
the gaps jump, or a state other than the last one returned is stepped.  Across a step
boundary with continuous inputs it simply integrates on, as ``simulate`` does across hold
intervals (a kink of the gap path is no jump of any unknown).

Linear algebra: IDAS's GMRES with this module's preconditioner, the Newton matrix
``c_j dF/dy' + dF/dy`` from the compiled Jacobian, factorised exactly, so that GMRES
converges in zero or one iteration; on either form of the flux DAE (``FluxDAE.form``).
The factorisation is a sparse LU on a fixed pattern (:func:`sparse_lu_plan`): at the first
restart SuperLU chooses a COLAMD column order and partial-pivoting row order on the Newton
matrix at that point, a symbolic elimination gives the fill, and every setup then runs a
left-looking numeric LU in C on that pattern with those pivots (static pivoting: no search,
no allocation).  A static pivot can become poor where the matrix changes; GMRES corrects an
inexact preconditioner, but a tiny pivot would make it useless, so a pivot below
:data:`PIVOT_TOLERANCE` times the largest entry of its column (after the updates) makes
that setup factorise densely with partial pivoting instead (the previous path: dense LU
updating only the nonzero rows of each pivot column).  On TR09's split network (373 DAE
unknowns, 2.2k Jacobian nonzeros, 8.7k in L and U) a factorisation costs ~90 us instead of
0.78 ms, and no setup of the benchmark run falls back.

Error test: as in ``simulate`` (CasADi's IDAS), every unknown is in IDAS's local error
test, so both paths integrate to the same tolerances.  On TR09's split network this holds
IDAS at about 5 steps per 1 ms call for stretches of a run (the first 200 ms of the
benchmark scenario, throughout with faster gap motion), against one step per call
elsewhere.  Leaving the loop fluxes and ``y'`` out of the test (``IDASetSuppressAlg``)
gave one step per call but 3-5x ``simulate``'s error at 20-50 Hz gap motion; measured,
not adopted (docs/decisions.md, livestep22).

The outputs are evaluated in C at the end of each step (the model's own output function,
generated into this library), not through a CasADi call from Python.

The SUNDIALS API used is that of the 2.x series CasADi bundles (``IDASpgmr``,
``IDASpilsSetPreconditioner``, serial ``N_Vector``); :func:`live_library` checks the
symbols and returns None where they are missing (then ``step`` keeps CasADi's integrator).
"""

from __future__ import annotations

import ctypes
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ParameterError, SolverError
from .compiled import DEFAULT_FLAGS, build_source, cache_directory

__all__ = ["LiveIntegrator", "live_library"]

_SUNDIALS_LIBS = ("libcasadi_integrator_idas.so", "libcasadi_sundials_common.so")

_DRIVER = r"""
/* ---- the SUNDIALS 2.x API (as bundled with CasADi) ---- */
typedef double realtype;
typedef struct _generic_N_Vector *N_Vector;
struct _generic_N_Vector { void *content; void *ops; };
struct fx_serial { long int length; int own_data; realtype *data; };
#define NVD(v) (((struct fx_serial *)((v)->content))->data)
extern N_Vector N_VNew_Serial(long int n);
extern void N_VDestroy_Serial(N_Vector v);
typedef int (*fx_res_fn)(realtype, N_Vector, N_Vector, N_Vector, void *);
typedef int (*fx_quad_fn)(realtype, N_Vector, N_Vector, N_Vector, void *);
typedef int (*fx_pset_fn)(realtype, N_Vector, N_Vector, N_Vector, realtype, void *,
                          N_Vector, N_Vector, N_Vector);
typedef int (*fx_psol_fn)(realtype, N_Vector, N_Vector, N_Vector, N_Vector, N_Vector,
                          realtype, realtype, void *, N_Vector);
typedef void (*fx_err_fn)(int, const char *, const char *, char *, void *);
extern void *IDACreate(void);
extern void IDAFree(void **mem);
extern int IDAInit(void *mem, fx_res_fn res, realtype t0, N_Vector yy0, N_Vector yp0);
extern int IDAReInit(void *mem, realtype t0, N_Vector yy0, N_Vector yp0);
extern int IDASVtolerances(void *mem, realtype rtol, N_Vector atol);
extern int IDASetUserData(void *mem, void *data);
extern int IDASetErrHandlerFn(void *mem, fx_err_fn f, void *data);
extern int IDASetMaxNumSteps(void *mem, long int n);
extern int IDASetId(void *mem, N_Vector id);
extern int IDASetStopTime(void *mem, realtype t);
extern int IDASpgmr(void *mem, int maxl);
extern int IDASpilsSetPreconditioner(void *mem, fx_pset_fn pset, fx_psol_fn psol);
extern int IDAQuadInit(void *mem, fx_quad_fn f, N_Vector q0);
extern int IDAQuadReInit(void *mem, N_Vector q0);
extern int IDAGetQuad(void *mem, realtype *t, N_Vector q);
extern int IDACalcIC(void *mem, int icopt, realtype tout1);
extern int IDASolve(void *mem, realtype tout, realtype *tret, N_Vector yret, N_Vector ypret,
                    int itask);
#include <stdlib.h>
#include <string.h>
#include <math.h>

typedef struct {
  void *mem;
  N_Vector yy, yp, q, id, atol;
  long int nx, nz, nn, np, nu, nq, ns, nw, nout, ng, nlc;
  double *p, *u, *M, *J[4], *w;
  long long int *iw, *piv, *nzr, *lp, *li, *up, *ui;
  double *lx, *ux;
  /* the sparse LU on a fixed pattern (fx_set_lu): columns cp/ri (permuted rows, ascending),
     diagonal positions dp, destinations of the Jacobian blocks' nonzeros (dest) and of the
     c_j diagonal (cjdest), row and column permutations pr/pc, values v, work x (zeros) */
  long long int lu_on, lu_sparse, *cp, *ri, *dp, *dest, *cjdest, *pr, *pc;
  double *v, *x, *c, lu_tol;
  long int n_sparse, n_dense, n_psol, n_nonfinite;
  const double **arg;
  double **res;
  const long long int *sp[4];
  char msg[400];
} fx_session;

static int fx_call(int which, fx_session *s, double t, const double *x, const double *z,
                   double **out) {
  s->arg[0] = &t; s->arg[1] = x; s->arg[2] = z; s->arg[3] = s->p; s->arg[4] = s->u;
  int k;
  for (k = 0; k < 4; ++k) s->res[k] = out[k];
  if (which == 0) return FX_DAE(s->arg, s->res, s->iw, s->w, 0);
  if (which == 1) return FX_JAC(s->arg, s->res, s->iw, s->w, 0);
  if (which == 2) return FX_QUAD(s->arg, s->res, s->iw, s->w, 0);
  if (which == 3) return FX_FORCE(s->arg, s->res, s->iw, s->w, 0);
  /* the outputs at the state vector w = x (y, gaps, loop fluxes, currents): (w, U, rate) */
  s->arg[0] = x; s->arg[1] = s->p; s->arg[2] = z;
  return FX_OUT(s->arg, s->res, s->iw, s->w, 0);
}

static int fx_res(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *data) {
  fx_session *s = (fx_session *)data;
  double *r = NVD(rr), *d = NVD(yp);
  double *out[4] = {r, r + s->nx, 0, 0};
  long int i;
  if (fx_call(0, s, t, NVD(yy), NVD(yy) + s->nx, out)) return -1;
  for (i = 0; i < s->nx; ++i) r[i] = d[i] - r[i];
  for (i = 0; i < s->nn; ++i) if (!isfinite(r[i])) return 1;   /* recoverable */
  return 0;
}

static int fx_quad(realtype t, N_Vector yy, N_Vector yp, N_Vector rq, void *data) {
  fx_session *s = (fx_session *)data;
  double *out[4] = {NVD(rq), 0, 0, 0};
  (void)yp;
  if (fx_call(2, s, t, NVD(yy), NVD(yy) + s->nx, out)) return -1;
  out[0] = NVD(rq) + FX_QUAD_N;       /* then the pole forces' integrals */
  return fx_call(3, s, t, NVD(yy), NVD(yy) + s->nx, out) ? -1 : 0;
}

/* scatter a CasADi CCS block into the dense column-major Newton matrix */
static void fx_scatter(fx_session *s, int k, long int r0, long int c0, double sign) {
  const long long int *sp = s->sp[k];
  long long int ncol = sp[1], c, e;
  const long long int *colind = sp + 2, *row = sp + 3 + ncol;
  for (c = 0; c < ncol; ++c)
    for (e = colind[c]; e < colind[c + 1]; ++e)
      s->M[(c0 + c) * s->nn + r0 + row[e]] += sign * s->J[k][e];
}

/* numeric LU of the Newton matrix on the fixed pattern, without pivoting (the orders come
   from fx_set_lu); left-looking, column by column; 0 where a pivot is below lu_tol times
   the largest entry of its column (then the caller factorises densely with pivoting) */
static int fx_sparse_lu(fx_session *s, double cj) {
  long long int n = s->nn, j, e, f, k, m = 0;
  double *v = s->v, *x = s->x;
  memset(v, 0, sizeof(double) * s->cp[n]);
  for (k = 0; k < 4; ++k) {            /* the Jacobian blocks, signs as in fx_scatter */
    const long long int *sp = s->sp[k];
    long long int nnz = sp[2 + sp[1]];
    double sign = (k == 0 || k == 2) ? -1.0 : 1.0;
    for (e = 0; e < nnz; ++e) v[s->dest[m + e]] += sign * s->J[k][e];
    m += nnz;
  }
  for (k = 0; k < s->nx; ++k) v[s->cjdest[k]] += cj;
  for (j = 0; j < n; ++j) {
    long long int a = s->cp[j], d = s->dp[j], b = s->cp[j + 1];
    double piv, big = 0.0;
    for (e = a; e < b; ++e) x[s->ri[e]] = v[e];
    for (e = a; e < d; ++e) {          /* U part: rows k < j in ascending order */
      double xk = x[s->ri[e]];
      k = s->ri[e];
      if (xk != 0.0)
        for (f = s->dp[k] + 1; f < s->cp[k + 1]; ++f) x[s->ri[f]] -= v[f] * xk;
    }
    for (e = d; e < b; ++e) if (fabs(x[s->ri[e]]) > big) big = fabs(x[s->ri[e]]);
    piv = x[j];
    /* a NaN anywhere in the column (fabs(NaN) > big is false, so the largest entry alone
       misses one below the diagonal or in U) makes this setup fall back too */
    for (e = a; e < b; ++e) if (!isfinite(x[s->ri[e]])) big = NAN;
    if (!(fabs(piv) >= s->lu_tol * big) || !(big > 0.0) || !isfinite(big)) {
      for (e = a; e < b; ++e) x[s->ri[e]] = 0.0;
      return 0;
    }
    for (e = a; e < d; ++e) v[e] = x[s->ri[e]];
    v[d] = piv;
    for (e = d + 1; e < b; ++e) v[e] = x[s->ri[e]] / piv;
    for (e = a; e < b; ++e) x[s->ri[e]] = 0.0;
  }
  return 1;
}

/* factorise the Newton matrix c_j dF/dy' + dF/dy of the Jacobian blocks in s->J: the
   sparse LU, else the dense LU with partial pivoting; 1 (recoverable) where the dense
   factors are not finite (a NaN or an infinity in the matrix) or a column is zero */
static int fx_factor(fx_session *s, realtype cj) {
  long int n = s->nn, nx = s->nx, i, j, k;
  if (s->lu_on) {
    if (fx_sparse_lu(s, cj)) { s->lu_sparse = 1; s->n_sparse++; return 0; }
  }
  s->n_dense++;           /* a tiny or non-finite static pivot, or no plan: dense LU */
  s->lu_sparse = 0;
  memset(s->M, 0, sizeof(double) * n * n);
  for (i = 0; i < nx; ++i) s->M[i * n + i] = cj;
  fx_scatter(s, 0, 0, 0, -1.0);      /* d ode / dx */
  fx_scatter(s, 1, nx, 0, 1.0);      /* d alg / dx */
  fx_scatter(s, 2, 0, nx, -1.0);     /* d ode / dz */
  fx_scatter(s, 3, nx, nx, 1.0);     /* d alg / dz */
  /* LU with partial pivoting, column-major, in place */
  for (k = 0; k < n; ++k) {
    long int p = k;
    double big = fabs(s->M[k * n + k]);
    for (i = k + 1; i < n; ++i)
      if (fabs(s->M[k * n + i]) > big) { big = fabs(s->M[k * n + i]); p = i; }
    s->piv[k] = p;
    if (!(big > 0.0) || !isfinite(big)) {                      /* recoverable */
      if (!(big == 0.0)) s->n_nonfinite++;
      return 1;
    }
    if (p != k)
      for (j = 0; j < n; ++j) {
        double tmp = s->M[j * n + k]; s->M[j * n + k] = s->M[j * n + p]; s->M[j * n + p] = tmp;
      }
    double inv = 1.0 / s->M[k * n + k];
    long int nz = 0, e;
    for (i = k + 1; i < n; ++i) {
      s->M[k * n + i] *= inv;
      if (s->M[k * n + i] != 0.0) s->nzr[nz++] = i;     /* the rows the update touches */
    }
    for (j = k + 1; j < n; ++j) {
      double a = s->M[j * n + k];
      if (a != 0.0)
        for (e = 0; e < nz; ++e) s->M[j * n + s->nzr[e]] -= a * s->M[k * n + s->nzr[e]];
    }
  }
  /* L (below the diagonal) and U (above) column by column, nonzeros only, for fx_psol */
  long long int cl = 0, cu = 0;
  for (k = 0; k < n; ++k) {
    s->lp[k] = cl; s->up[k] = cu;
    /* a NaN passes the pivot search (fabs(NaN) > big is false) and spreads through the
       updates into L and U: any non-finite factor fails this setup (recoverable) */
    if (!isfinite(s->M[k * n + k])) { s->n_nonfinite++; return 1; }
    for (i = k + 1; i < n; ++i)
      if (s->M[k * n + i] != 0.0) {
        if (!isfinite(s->M[k * n + i])) { s->n_nonfinite++; return 1; }
        s->li[cl] = i; s->lx[cl++] = s->M[k * n + i];
      }
    for (i = 0; i < k; ++i)
      if (s->M[k * n + i] != 0.0) {
        if (!isfinite(s->M[k * n + i])) { s->n_nonfinite++; return 1; }
        s->ui[cu] = i; s->ux[cu++] = s->M[k * n + i];
      }
  }
  s->lp[n] = cl; s->up[n] = cu;
  return 0;
}

static int fx_pset(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, realtype cj, void *data,
                   N_Vector t1, N_Vector t2, N_Vector t3) {
  fx_session *s = (fx_session *)data;
  (void)yp; (void)rr; (void)t1; (void)t2; (void)t3;
  if (fx_call(1, s, t, NVD(yy), NVD(yy) + s->nx, s->J)) return -1;
  return fx_factor(s, cj);
}

static int fx_psol(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, N_Vector rv, N_Vector zv,
                   realtype cj, realtype delta, void *data, N_Vector tmp) {
  fx_session *s = (fx_session *)data;
  long int n = s->nn, k;
  long long int e;
  double *z = NVD(zv), *r = NVD(rv);
  (void)t; (void)yy; (void)yp; (void)rr; (void)cj; (void)delta; (void)tmp;
  s->n_psol++;
  if (s->lu_sparse) {                  /* z = Pc U^-1 L^-1 Pr r */
    double *c = s->c, *v = s->v;
    for (k = 0; k < n; ++k) c[s->pr[k]] = r[k];
    for (k = 0; k < n; ++k) {
      double ck = c[k];
      if (ck != 0.0)
        for (e = s->dp[k] + 1; e < s->cp[k + 1]; ++e) c[s->ri[e]] -= v[e] * ck;
    }
    for (k = n - 1; k >= 0; --k) {
      double ck = c[k] / v[s->dp[k]];
      c[k] = ck;
      if (ck != 0.0)
        for (e = s->cp[k]; e < s->dp[k]; ++e) c[s->ri[e]] -= v[e] * ck;
    }
    for (k = 0; k < n; ++k) z[k] = c[s->pc[k]];
    return 0;
  }
  memcpy(z, r, sizeof(double) * n);
  for (k = 0; k < n; ++k) {                /* the row swaps (LAPACK order), then L */
    long int p = s->piv[k];
    if (p != k) { double a = z[k]; z[k] = z[p]; z[p] = a; }
  }
  /* the dense loops' operations in their order, without the zero entries of L and U (and
     of z: subtracting a zero product changes nothing) */
  for (k = 0; k < n; ++k)
    if (z[k] != 0.0)
      for (e = s->lp[k]; e < s->lp[k + 1]; ++e) z[s->li[e]] -= s->lx[e] * z[k];
  for (k = n - 1; k >= 0; --k) {
    z[k] /= s->M[k * n + k];
    if (z[k] != 0.0)
      for (e = s->up[k]; e < s->up[k + 1]; ++e) z[s->ui[e]] -= s->ux[e] * z[k];
  }
  return 0;
}

static void fx_err(int code, const char *module, const char *function, char *msg, void *data) {
  fx_session *s = (fx_session *)data;
  (void)code; (void)module; (void)function;
  strncpy(s->msg, msg, sizeof(s->msg) - 1);
}

void fx_free(void *data);

static long long int fx_max(long long int a, long long int b) { return a > b ? a : b; }

void *fx_new(long int nx, long int nz, long int np, long int nu, long int nq, long int ng,
             long int nlc, double rtol, const double *atol, long int max_steps) {
  fx_session *s = (fx_session *)calloc(1, sizeof(fx_session));
  long long int a, r, i, w, sa = 0, sr = 0, si = 0, sw = 0;
  long int k;
  if (!s) return 0;
  s->nx = nx; s->nz = nz; s->nn = nx + nz; s->np = np; s->nu = nu; s->nq = nq;
  s->ng = ng; s->nlc = nlc; s->nw = nx + ng + nlc;
  FX_DAE_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_JAC_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_QUAD_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_FORCE_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_OUT_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  s->arg = (const double **)calloc(fx_max(sa, 5), sizeof(double *));
  s->res = (double **)calloc(fx_max(sr, 4), sizeof(double *));
  s->iw = (long long int *)calloc(si + 1, sizeof(long long int));
  s->w = (double *)calloc(sw + 1, sizeof(double));
  s->p = (double *)calloc(np + 1, sizeof(double));
  s->u = (double *)calloc(nu + 1, sizeof(double));
  s->M = (double *)calloc(s->nn * s->nn, sizeof(double));
  s->piv = (long long int *)calloc(s->nn, sizeof(long long int));
  s->nzr = (long long int *)calloc(s->nn, sizeof(long long int));
  s->lp = (long long int *)calloc(s->nn + 1, sizeof(long long int));
  s->up = (long long int *)calloc(s->nn + 1, sizeof(long long int));
  s->li = (long long int *)calloc(s->nn * s->nn, sizeof(long long int));
  s->ui = (long long int *)calloc(s->nn * s->nn, sizeof(long long int));
  s->lx = (double *)calloc(s->nn * s->nn, sizeof(double));
  s->ux = (double *)calloc(s->nn * s->nn, sizeof(double));
  for (k = 0; k < 4; ++k) {
    const long long int *sp = FX_JAC_sparsity_out(k);
    s->sp[k] = sp;
    s->J[k] = (double *)calloc(sp[2 + sp[1]] + 1, sizeof(double));
    if (!s->J[k]) { fx_free(s); return 0; }
  }
  if (!s->arg || !s->res || !s->iw || !s->w || !s->p || !s->u || !s->M || !s->piv || !s->nzr
      || !s->lp || !s->up || !s->li || !s->ui || !s->lx || !s->ux) {
    fx_free(s); return 0;
  }
  s->yy = N_VNew_Serial(s->nn); s->yp = N_VNew_Serial(s->nn);
  s->q = N_VNew_Serial(nq); s->id = N_VNew_Serial(s->nn); s->atol = N_VNew_Serial(s->nn);
  if (!s->yy || !s->yp || !s->q || !s->id || !s->atol) { fx_free(s); return 0; }
  memset(NVD(s->yy), 0, sizeof(double) * s->nn); memset(NVD(s->yp), 0, sizeof(double) * s->nn);
  memset(NVD(s->q), 0, sizeof(double) * nq);
  for (k = 0; k < s->nn; ++k) { NVD(s->id)[k] = k < nx ? 1.0 : 0.0; NVD(s->atol)[k] = atol[k]; }
  s->mem = IDACreate();
  if (!s->mem || IDAInit(s->mem, fx_res, 0.0, s->yy, s->yp) || IDASetUserData(s->mem, s)
      || IDASetErrHandlerFn(s->mem, fx_err, s) || IDASVtolerances(s->mem, rtol, s->atol)
      || IDASetMaxNumSteps(s->mem, max_steps) || IDASetId(s->mem, s->id)
      || IDASpgmr(s->mem, 5) || IDASpilsSetPreconditioner(s->mem, fx_pset, fx_psol)
      || IDAQuadInit(s->mem, fx_quad, s->q)) {
    fx_free(s);                      /* no leak of the half-built session */
    return 0;
  }
  return s;
}

/* restart at normalised time t0 from differential x0 and algebraic guess z0 (inputs p, u);
   consistent initial condition as CasADi's integrator computes it */
int fx_reinit(void *data, double t0, const double *x0, const double *z0, const double *p,
              const double *u) {
  fx_session *s = (fx_session *)data;
  double *y = NVD(s->yy), *d = NVD(s->yp);
  double *out[4] = {d, d + s->nx, 0, 0};
  s->msg[0] = 0;
  memcpy(s->p, p, sizeof(double) * s->np); memcpy(s->u, u, sizeof(double) * s->nu);
  memcpy(y, x0, sizeof(double) * s->nx); memcpy(y + s->nx, z0, sizeof(double) * s->nz);
  if (fx_call(0, s, t0, y, y + s->nx, out)) return -99;       /* y' guess: the ODE */
  memset(d + s->nx, 0, sizeof(double) * s->nz);
  memset(NVD(s->q), 0, sizeof(double) * s->nq);
  int flag = IDAReInit(s->mem, t0, s->yy, s->yp);
  if (!flag) flag = IDAQuadReInit(s->mem, s->q);
  if (!flag) flag = IDACalcIC(s->mem, 1 /* IDA_YA_YDP_INIT */, t0 + 1.0);
  return flag;
}

/* integrate to tout with the interval's inputs u = (h, start gaps, gap rates, tau): the
   state vector w at tout (differential unknowns, end gaps start + rate h, loop fluxes,
   currents), the quadratures since the last reinit and the outputs at (w, p, rate) */
int fx_step(void *data, double tout, const double *u, double *w_out, double *q_out,
            double *o_out) {
  fx_session *s = (fx_session *)data;
  double t, *y = NVD(s->yy), *out[4] = {o_out, 0, 0, 0};
  long int k;
  s->msg[0] = 0;
  memcpy(s->u, u, sizeof(double) * s->nu);
  int flag = IDASetStopTime(s->mem, tout);
  if (!flag) flag = IDASolve(s->mem, tout, &t, s->yy, s->yp, 1 /* IDA_NORMAL */);
  if (flag < 0) return flag;
  flag = IDAGetQuad(s->mem, &t, s->q);
  if (flag < 0) return flag;
  memcpy(q_out, NVD(s->q), sizeof(double) * s->nq);
  memcpy(w_out, y, sizeof(double) * s->nx);
  for (k = 0; k < s->ng; ++k) w_out[s->nx + k] = u[1 + k] + u[1 + s->ng + k] * u[0];
  memcpy(w_out + s->nx + s->ng, y + s->nx, sizeof(double) * s->nlc);
  return fx_call(4, s, t, w_out, u + 1 + s->ng, out) ? -98 : 0;
}

/* the sparse LU's plan (from sparse_lu_plan): nnz entries in n columns */
int fx_set_lu(void *data, long long int nnz, const long long int *cp, const long long int *ri,
              const long long int *dp, const long long int *dest, const long long int *cjdest,
              const long long int *pr, const long long int *pc, double tol) {
  fx_session *s = (fx_session *)data;
  long long int n = s->nn, nj = 0, k;
  for (k = 0; k < 4; ++k) nj += s->sp[k][2 + s->sp[k][1]];
  free(s->cp); free(s->ri); free(s->dp); free(s->dest); free(s->cjdest); free(s->pr);
  free(s->pc); free(s->v); free(s->x); free(s->c);
  s->cp = s->ri = s->dp = s->dest = s->cjdest = s->pr = s->pc = 0;
  s->v = s->x = s->c = 0;
  s->lu_on = s->lu_sparse = 0;
  if (nnz <= 0) return 0;                /* no plan: the dense LU */
  s->cp = (long long int *)malloc(sizeof(long long int) * (n + 1));
  s->ri = (long long int *)malloc(sizeof(long long int) * (nnz + 1));
  s->dp = (long long int *)malloc(sizeof(long long int) * n);
  s->dest = (long long int *)malloc(sizeof(long long int) * (nj + 1));
  s->cjdest = (long long int *)malloc(sizeof(long long int) * (s->nx + 1));
  s->pr = (long long int *)malloc(sizeof(long long int) * n);
  s->pc = (long long int *)malloc(sizeof(long long int) * n);
  s->v = (double *)malloc(sizeof(double) * (nnz + 1));
  s->x = (double *)calloc(n, sizeof(double));
  s->c = (double *)calloc(n, sizeof(double));
  if (!s->cp || !s->ri || !s->dp || !s->dest || !s->cjdest || !s->pr || !s->pc || !s->v
      || !s->x || !s->c) return -1;
  memcpy(s->cp, cp, sizeof(long long int) * (n + 1));
  memcpy(s->ri, ri, sizeof(long long int) * nnz);
  memcpy(s->dp, dp, sizeof(long long int) * n);
  memcpy(s->dest, dest, sizeof(long long int) * nj);
  memcpy(s->cjdest, cjdest, sizeof(long long int) * s->nx);
  memcpy(s->pr, pr, sizeof(long long int) * n);
  memcpy(s->pc, pc, sizeof(long long int) * n);
  s->lu_tol = tol;
  s->lu_on = nnz > 0;
  return 0;
}

/* the preconditioner at one point (for tests): set up at (t, x, z) with inputs p, u and
   c_j, then out = M^-1 rhs; 1 where the sparse LU was used, 0 the dense LU, -1 on failure.
   With jac (not NULL) the Jacobian blocks' nonzeros are these values (concatenated, as
   fx_jacobian gives them) instead of the ones at the point.  It replaces the
   preconditioner IDAS set up last (GMRES corrects a stale one); the inputs IDAS
   integrates with are restored. */
int fx_newton_solve(void *data, double t, const double *x, const double *z, const double *p,
                    const double *u, double cj, const double *rhs, const double *jac,
                    double *out) {
  fx_session *s = (fx_session *)data;
  N_Vector y = N_VNew_Serial(s->nn), r = N_VNew_Serial(s->nn), o = N_VNew_Serial(s->nn);
  double *p0 = (double *)malloc(sizeof(double) * (s->np + s->nu + 1));
  int flag = -1;
  if (y && r && o && p0) {
    memcpy(p0, s->p, sizeof(double) * s->np); memcpy(p0 + s->np, s->u, sizeof(double) * s->nu);
    memcpy(s->p, p, sizeof(double) * s->np); memcpy(s->u, u, sizeof(double) * s->nu);
    memcpy(NVD(y), x, sizeof(double) * s->nx); memcpy(NVD(y) + s->nx, z, sizeof(double) * s->nz);
    memcpy(NVD(r), rhs, sizeof(double) * s->nn);
    int set;
    if (jac) {
      long long int m = 0;
      int k;
      for (k = 0; k < 4; ++k) {
        long long int nnz = s->sp[k][2 + s->sp[k][1]];
        memcpy(s->J[k], jac + m, sizeof(double) * nnz);
        m += nnz;
      }
      set = fx_factor(s, cj);
    } else {
      set = fx_pset(t, y, y, y, cj, s, y, y, y);
    }
    if (!set && !fx_psol(t, y, y, y, r, o, cj, 0.0, s, y)) {
      memcpy(out, NVD(o), sizeof(double) * s->nn);
      flag = s->lu_sparse ? 1 : 0;
    }
    memcpy(s->p, p0, sizeof(double) * s->np); memcpy(s->u, p0 + s->np, sizeof(double) * s->nu);
  }
  if (y) N_VDestroy_Serial(y);
  if (r) N_VDestroy_Serial(r);
  if (o) N_VDestroy_Serial(o);
  free(p0);
  return flag;
}

/* the compressed-column sparsity of Jacobian block k (CasADi's format) */
const long long int *fx_jac_sparsity(void *data, int k) {
  return ((fx_session *)data)->sp[k];
}

/* the Jacobian blocks' nonzeros, concatenated, at (t, x, z) with inputs p, u */
int fx_jacobian(void *data, double t, const double *x, const double *z, const double *p,
                const double *u, double *out) {
  fx_session *s = (fx_session *)data;
  long long int m = 0;
  int k;
  memcpy(s->p, p, sizeof(double) * s->np); memcpy(s->u, u, sizeof(double) * s->nu);
  if (fx_call(1, s, t, x, z, s->J)) return -1;
  for (k = 0; k < 4; ++k) {
    long long int nnz = s->sp[k][2 + s->sp[k][1]];
    memcpy(out + m, s->J[k], sizeof(double) * nnz);
    m += nnz;
  }
  return 0;
}

extern int IDAGetNumSteps(void *mem, long int *n);
extern int IDAGetNumResEvals(void *mem, long int *n);
extern int IDAGetNumNonlinSolvIters(void *mem, long int *n);
extern int IDAGetNumErrTestFails(void *mem, long int *n);
extern int IDASpilsGetNumLinIters(void *mem, long int *n);

/* counters: sparse and dense factorisations, preconditioner solves (since fx_new); IDAS's
   steps, residual evaluations, Newton and GMRES iterations, error test failures (since the
   last restart); setups refused for a non-finite matrix or factor (since fx_new) */
void fx_stats(void *data, double *out) {
  fx_session *s = (fx_session *)data;
  long int v = 0;
  out[0] = (double)s->n_sparse; out[1] = (double)s->n_dense; out[2] = (double)s->n_psol;
  out[8] = (double)s->n_nonfinite;
  IDAGetNumSteps(s->mem, &v); out[3] = (double)v;
  IDAGetNumResEvals(s->mem, &v); out[4] = (double)v;
  IDAGetNumNonlinSolvIters(s->mem, &v); out[5] = (double)v;
  IDASpilsGetNumLinIters(s->mem, &v); out[6] = (double)v;
  IDAGetNumErrTestFails(s->mem, &v); out[7] = (double)v;
}

const char *fx_message(void *data) { return ((fx_session *)data)->msg; }

void fx_free(void *data) {
  fx_session *s = (fx_session *)data;
  int k;
  if (!s) return;
  if (s->mem) IDAFree(&s->mem);
  if (s->yy) N_VDestroy_Serial(s->yy);
  if (s->yp) N_VDestroy_Serial(s->yp);
  if (s->q) N_VDestroy_Serial(s->q);
  if (s->id) N_VDestroy_Serial(s->id);
  if (s->atol) N_VDestroy_Serial(s->atol);
  for (k = 0; k < 4; ++k) free(s->J[k]);
  free(s->arg); free(s->res); free(s->iw); free(s->w); free(s->p); free(s->u); free(s->M);
  free(s->piv); free(s->nzr); free(s->lp); free(s->up); free(s->li); free(s->ui);
  free(s->lx); free(s->ux);
  free(s->cp); free(s->ri); free(s->dp); free(s->dest); free(s->cjdest); free(s->pr);
  free(s->pc); free(s->v); free(s->x); free(s->c); free(s);
}
"""


#: a static pivot below this fraction of the largest entry of its column (after the updates
#: of the columns before it) makes that setup factorise densely with partial pivoting
PIVOT_TOLERANCE = 1e-3

#: c_j (IDAS's ``alpha / h`` in the normalised time of one hold interval) of the matrix the
#: pivot order is chosen on: large, so that the differential unknowns pivot on their own
#: ``c_j`` diagonal (at every smaller ``c_j`` these pivots stay within PIVOT_TOLERANCE of
#: the ``-1`` of ``D x - y`` in the same column down to ``c_j = 1e-3``)
PLAN_CJ = 1e3


def newton_entries(sparsities: list[np.ndarray], nx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and signs of the Newton matrix entries of the four Jacobian blocks
    (``d ode/dx``, ``d alg/dx``, ``d ode/dz``, ``d alg/dz``, each CasADi's compressed
    columns), in the order of their nonzeros."""
    rows, cols, signs = [], [], []
    for k, sp in enumerate(sparsities):
        ncol = int(sp[1])
        colind = sp[2:3 + ncol]
        row = sp[3 + ncol:3 + ncol + int(colind[-1])]
        col = np.repeat(np.arange(ncol), np.diff(colind))
        rows.append(row + (nx if k in (1, 3) else 0))
        cols.append(col + (nx if k in (2, 3) else 0))
        signs.append(np.full(row.size, -1.0 if k in (0, 2) else 1.0))
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(signs)


def sparse_lu_plan(sparsities: list[np.ndarray], nx: int, values: np.ndarray,
                   cj: float = PLAN_CJ) -> dict[str, np.ndarray] | None:
    """The fixed-pattern sparse LU of the Newton matrix ``c_j dF/dy' + dF/dy``: orders and
    fill, chosen once per model on one matrix.

    SuperLU (scipy's ``splu``) factorises the matrix at ``values`` with a COLAMD column
    order and partial pivoting; its row and column permutations are kept as a static
    order, and a symbolic elimination on the permuted pattern gives every entry of L and U
    that the numeric factorisation without pivoting can fill (values at other points with
    the same sparsity never fill elsewhere).

    Parameters
    ----------
    sparsities : list of 4 ndarray
        CasADi's compressed-column sparsity of ``d ode/dx``, ``d alg/dx``, ``d ode/dz``,
        ``d alg/dz``.
    nx : int
        Differential unknowns (the first ``nx`` get ``c_j`` on the diagonal).
    values : ndarray
        The four blocks' nonzeros, concatenated (a representative point).
    cj : float
        ``c_j`` of the representative matrix.

    Returns
    -------
    dict or None
        ``cp``, ``ri``, ``dp`` (columns of L and U together: column pointers, permuted
        rows ascending, diagonal positions), ``dest`` (storage position of every Jacobian
        nonzero), ``cjdest`` (of the ``c_j`` diagonal), ``pr``, ``pc`` (original row and
        column -> permuted position), or None where SuperLU finds the matrix singular.
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    rows, cols, signs = newton_entries(sparsities, nx)
    n = int(sparsities[3][0]) + nx
    diag = np.arange(nx)
    A = sp.csc_matrix((np.concatenate((signs * values, np.full(nx, cj))),
                       (np.concatenate((rows, diag)), np.concatenate((cols, diag)))),
                      shape=(n, n))
    try:
        lu = spla.splu(A, permc_spec="COLAMD")
    except RuntimeError:          # exactly singular at this point
        return None
    pr, pc = lu.perm_r.astype(np.int64), lu.perm_c.astype(np.int64)
    # symbolic elimination without pivoting on the permuted pattern (diagonal included)
    prow, pcol = pr[np.concatenate((rows, diag))], pc[np.concatenate((cols, diag))]
    in_row: list[set[int]] = [set() for _ in range(n)]
    in_col: list[set[int]] = [set() for _ in range(n)]
    for i, j in zip(prow.tolist(), pcol.tolist(), strict=True):
        in_row[i].add(j)
        in_col[j].add(i)
    for k in range(n):
        in_row[k].add(k)
        in_col[k].add(k)
    for k in range(n):
        lower = [i for i in in_col[k] if i > k]
        upper = [j for j in in_row[k] if j > k]
        for i in lower:
            row_i = in_row[i]
            for j in upper:
                if j not in row_i:
                    row_i.add(j)
                    in_col[j].add(i)
    cp = np.zeros(n + 1, dtype=np.int64)
    ri_cols = [np.array(sorted(c), dtype=np.int64) for c in in_col]
    cp[1:] = np.cumsum([c.size for c in ri_cols])
    ri = np.concatenate(ri_cols)
    dp = np.array([cp[j] + np.searchsorted(ri_cols[j], j) for j in range(n)], dtype=np.int64)

    def position(i: np.ndarray, j: np.ndarray) -> np.ndarray:
        return np.array([cp[b] + np.searchsorted(ri_cols[b], a) for a, b in
                         zip(i.tolist(), j.tolist(), strict=True)], dtype=np.int64)

    return {"cp": cp, "ri": ri, "dp": dp, "dest": position(pr[rows], pc[cols]),
            "cjdest": position(pr[diag], pc[diag]), "pr": pr, "pc": pc}


def _sundials_paths() -> list[Path] | None:
    base = Path(ca.__file__).parent
    paths = [base / n for n in _SUNDIALS_LIBS]
    return paths if all(p.exists() for p in paths) else None


def live_library(dae_f: ca.Function, jac_f: ca.Function, quad_f: ca.Function,
                 force_f: ca.Function, out_f: ca.Function, cache_dir: str | None,
                 flags: tuple[str, ...] = DEFAULT_FLAGS) -> Path | None:
    """The compiled live-integrator library of one flux DAE (cached on disk by content), or
    None where CasADi ships no IDAS library to link against or compiling fails.

    Parameters
    ----------
    dae_f, jac_f, quad_f : casadi.Function
        The ``daeF``, ``jacF`` and ``quadF`` functions of the flux model's IDAS integrator.
    force_f : casadi.Function
        The pole forces [N] (times the interval length) on the same arguments: integrated
        as further quadratures, so the mechanical work ``-rate . int F dt`` of an interval
        has no integrand that jumps where the gap rate does.
    out_f : casadi.Function
        The model's outputs ``(w, U, rate) -> outputs`` (``FluxDAE.output_fun``), evaluated
        in C at the end of every step.
    cache_dir : str or None
        The compiled-library cache (default :func:`~maglevkit.models.compiled.cache_directory`).
    flags : tuple of str
        Compiler flags (the linker options for the IDAS library are added).
    """
    libs = _sundials_paths()
    if libs is None:
        return None
    cg = ca.CodeGenerator("maglevkit_flux_live", {"with_header": False})
    for f in (dae_f, jac_f, quad_f, force_f, out_f):
        cg.add(f)
    names = {"FX_DAE": dae_f.name(), "FX_JAC": jac_f.name(), "FX_QUAD": quad_f.name(),
             "FX_FORCE": force_f.name(), "FX_OUT": out_f.name()}
    defines = "".join(f"#define {k} {v}\n#define {k}_work {v}_work\n"
                      f"#define {k}_sparsity_out {v}_sparsity_out\n" for k, v in names.items())
    defines += f"#define FX_QUAD_N {quad_f.numel_out(0)}\n"
    code = (cg.dump() + "\n" + defines + _DRIVER).encode()
    # -z defs (GNU ld, Linux): a symbol the IDAS libraries lack fails the link here, not
    # the first step at run time
    defs = ("-Wl,-z,defs",) if sys.platform.startswith("linux") else ()
    flags = (*flags, *defs, "-Wl,--no-as-needed", *map(str, libs),
             f"-Wl,-rpath,{libs[0].parent}")
    cache = Path(cache_dir) if cache_dir is not None else cache_directory()
    try:
        return build_source("maglevkit_flux_live", code, cache=cache, flags=flags)
    except (OSError, RuntimeError, subprocess.SubprocessError):
        return None


class LiveIntegrator:
    """One IDAS memory over a flux DAE: :meth:`reinit` (restart with a consistent initial
    condition) and :meth:`step` (integrate on to the next interval end).

    Parameters
    ----------
    library : Path
        From :func:`live_library`.
    nx, nz, np_, nu, nq : int
        Differential and algebraic unknowns, DAE parameters (voltages), interval inputs and
        quadratures.
    ng, nlc, nout : int
        Gaps, loop fluxes + currents (the algebraic unknowns of the state vector) and
        outputs.
    rtol : float
        Relative tolerance.
    atol : ndarray (nx + nz,)
        Absolute tolerances of the unknowns.
    max_num_steps : int
        IDAS step limit per call.
    """

    def __init__(self, library: Path, nx: int, nz: int, np_: int, nu: int, nq: int, ng: int,
                 nlc: int, nout: int, rtol: float, atol: np.ndarray,
                 max_num_steps: int) -> None:
        lib = ctypes.CDLL(os.fspath(library))
        dp = ctypes.POINTER(ctypes.c_double)
        lib.fx_new.restype = ctypes.c_void_p
        lib.fx_new.argtypes = [ctypes.c_long] * 7 + [ctypes.c_double, dp, ctypes.c_long]
        lib.fx_reinit.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp, dp]
        lib.fx_step.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp, dp]
        lib.fx_message.restype = ctypes.c_char_p
        lib.fx_message.argtypes = [ctypes.c_void_p]
        lib.fx_free.argtypes = [ctypes.c_void_p]
        lp = ctypes.POINTER(ctypes.c_longlong)
        lib.fx_set_lu.argtypes = [ctypes.c_void_p, ctypes.c_longlong, *[lp] * 7,
                                  ctypes.c_double]
        lib.fx_jac_sparsity.restype = lp
        lib.fx_jac_sparsity.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.fx_jacobian.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp, dp, dp]
        lib.fx_stats.argtypes = [ctypes.c_void_p, dp]
        lib.fx_newton_solve.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp, dp,
                                        ctypes.c_double, dp, dp, dp]
        self._lib = lib
        self._lp = lp
        #: the sparse LU plan (None: not made yet, False: none; dense LU every setup)
        self.plan: dict[str, np.ndarray] | None | bool = None
        self._dp = dp
        self.nx, self.nz, self.nq = nx, nz, nq
        atol = np.ascontiguousarray(atol, dtype=float)
        self._nonfinite_reported = 0
        self._mem = lib.fx_new(nx, nz, np_, nu, nq, ng, nlc, rtol, atol.ctypes.data_as(dp),
                               max_num_steps)
        if not self._mem:
            raise RuntimeError("IDAS could not be set up")
        # step's buffers and their ctypes pointers, made once (a pointer costs a few us)
        self._u, self._w = np.empty(nu), np.empty(nx + ng + nlc)
        self._q, self._o = np.empty(nq), np.empty(nout)
        self._bufs = [a.ctypes.data_as(dp) for a in (self._u, self._w, self._q, self._o)]

    def _ptr(self, a: np.ndarray) -> Any:
        return a.ctypes.data_as(self._dp)

    def message(self) -> str:
        """The last message IDAS reported (empty if none)."""
        return (self._lib.fx_message(self._mem) or b"").decode(errors="replace")

    def sparsities(self) -> list[np.ndarray]:
        """CasADi's compressed-column sparsity of the four Jacobian blocks."""
        out = []
        for k in range(4):
            ptr = self._lib.fx_jac_sparsity(self._mem, k)
            ncol = int(ptr[1])
            nnz = int(ptr[2 + ncol])
            out.append(np.ctypeslib.as_array(ptr, shape=(3 + ncol + nnz,)).copy())
        return out

    def jacobian(self, t: float, x: np.ndarray, z: np.ndarray, p: np.ndarray,
                 u: np.ndarray) -> np.ndarray:
        """The four Jacobian blocks' nonzeros, concatenated, at one point."""
        out = np.empty(self.jacobian_size())
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (x, z, p, u)]
        if self._lib.fx_jacobian(self._mem, t, *map(self._ptr, arrays), self._ptr(out)):
            raise RuntimeError("the Jacobian could not be evaluated")
        return out

    def newton_solve(self, t: float, x: np.ndarray, z: np.ndarray, p: np.ndarray,
                     u: np.ndarray, cj: float, rhs: np.ndarray,
                     jacobian: np.ndarray | None = None) -> tuple[np.ndarray, bool]:
        """The preconditioner at one point: ``(M^-1 rhs, whether the sparse LU was used)``
        with ``M = c_j dF/dy' + dF/dy`` (for tests; it replaces the preconditioner IDAS set
        up last, which GMRES tolerates).  ``jacobian``: the Jacobian blocks' nonzeros to
        factorise instead of those at the point (as :meth:`jacobian` gives them).

        Raises
        ------
        SolverError
            The matrix could not be factorised: a non-finite entry (NaN or infinity, which
            no pivoting can factorise) or a zero column.
        """
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (x, z, p, u, rhs)]
        jac = None
        if jacobian is not None:
            jac = np.ascontiguousarray(jacobian, dtype=float)
            if jac.shape != (self.jacobian_size(),):
                raise ParameterError(f"newton_solve: jacobian of shape {jac.shape}; allowed "
                                     f"is ({self.jacobian_size()},), the blocks' nonzeros")
        out = np.empty(self.nx + self.nz)
        before = self.stats()["nonfinite_setups"]
        flag = self._lib.fx_newton_solve(self._mem, t, *map(self._ptr, arrays[:4]), cj,
                                         self._ptr(arrays[4]),
                                         None if jac is None else self._ptr(jac), self._ptr(out))
        if flag < 0:
            why = ("a non-finite entry (NaN or infinity) in the matrix or its LU factors"
                   if self.stats()["nonfinite_setups"] > before else "a zero column")
            raise SolverError(f"the Newton matrix could not be factorised: {why}",
                              reason=why)
        return out, bool(flag)

    def jacobian_size(self) -> int:
        """The number of the four Jacobian blocks' nonzeros (:meth:`jacobian`)."""
        return sum(int(sp[2 + int(sp[1])]) for sp in self.sparsities())

    def set_plan(self, plan: dict[str, np.ndarray] | None,
                 tolerance: float = PIVOT_TOLERANCE) -> None:
        """Factorise on ``plan`` (from :func:`sparse_lu_plan`) from now on, falling back to
        the dense LU where a static pivot is below ``tolerance`` times its column's largest
        entry (> 0: a zero pivot always falls back; ``inf``: every setup falls back); None:
        the dense LU at every setup.  ParameterError for a ``tolerance`` not > 0."""
        if not (isinstance(tolerance, (int, float)) and tolerance > 0):
            raise ParameterError(f"set_plan: tolerance = {tolerance!r}; allowed is a number "
                                 "> 0 (0 would let a zero pivot through)")
        if plan is None:
            self._lib.fx_set_lu(self._mem, 0, *[None] * 7, tolerance)
            self.plan = False
            return
        arrays = [np.ascontiguousarray(plan[k], dtype=np.int64)
                  for k in ("cp", "ri", "dp", "dest", "cjdest", "pr", "pc")]
        ptrs = [a.ctypes.data_as(self._lp) for a in arrays]
        if self._lib.fx_set_lu(self._mem, int(plan["cp"][-1]), *ptrs, tolerance):
            raise MemoryError("no memory for the sparse LU")
        self.plan = plan

    def stats(self) -> dict[str, int]:
        """Counters: ``sparse_setups``, ``dense_setups`` (fallbacks and setups without a
        plan), ``precond_solves`` (since creation); IDAS's ``steps``, ``residuals``,
        ``newton_iters``, ``gmres_iters``, ``error_test_fails`` (since the last restart);
        ``nonfinite_setups``: setups refused for a NaN or an infinity in the Newton matrix
        or its dense LU factors (since creation; IDAS then retries with a shorter step)."""
        out = np.zeros(9)
        self._lib.fx_stats(self._mem, self._ptr(out))
        keys = ("sparse_setups", "dense_setups", "precond_solves", "steps", "residuals",
                "newton_iters", "gmres_iters", "error_test_fails", "nonfinite_setups")
        return dict(zip(keys, map(int, out), strict=True))

    def reinit(self, t0: float, x0: np.ndarray, z0: np.ndarray, p: np.ndarray,
               u: np.ndarray) -> None:
        """Restart at normalised time ``t0``; RuntimeError (IDAS's message) on failure.

        The first restart chooses the sparse LU's plan on the Newton matrix at this point
        (:func:`sparse_lu_plan`)."""
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (x0, z0, p, u)]
        if self.plan is None:
            self.set_plan(sparse_lu_plan(self.sparsities(), self.nx,
                                         self.jacobian(t0, *arrays)))
        flag = self._lib.fx_reinit(self._mem, t0, *map(self._ptr, arrays))
        if flag < 0:
            raise RuntimeError(self.message() or f"IDAS initialisation flag {flag}")

    def step(self, tout: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Integrate to ``tout`` with interval inputs ``u`` = (h, start gaps, gap rates,
        tau): new arrays (state vector ``w`` at ``tout``, quadratures since the last
        :meth:`reinit`, outputs at ``w``)."""
        self._u[:] = u
        flag = self._lib.fx_step(self._mem, tout, *self._bufs)
        if flag == -98:
            raise RuntimeError("the outputs could not be evaluated")
        if flag < 0:
            # the counter is read on failure only (a step is a few tens of us)
            total = self.stats()["nonfinite_setups"]
            bad, self._nonfinite_reported = total - self._nonfinite_reported, total
            why = (f" ({bad} preconditioner setups since the last failure refused: a NaN or "
                   "an infinity in the Newton matrix or its LU factors)" if bad else "")
            raise RuntimeError((self.message() or f"IDAS flag {flag}") + why)
        return self._w.copy(), self._q.copy(), self._o.copy()

    def __del__(self) -> None:
        mem, self._mem = getattr(self, "_mem", None), None
        if mem:
            self._lib.fx_free(mem)
