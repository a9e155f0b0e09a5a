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

Linear algebra: IDAS's GMRES with this module's exact preconditioner (the Newton matrix
``dF/dy + c_j dF/dy'`` from the compiled Jacobian, factorised by dense LU with partial
pivoting, updating only the nonzero rows of each pivot column, so that the Newton matrices of
the sparse form, a few hundred unknowns with a few entries per row, factorise at a fraction
of the dense cost), so GMRES converges in one or two iterations; on either form of the flux
DAE (``FluxDAE.form``).

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
  long int nx, nz, nn, np, nu, nq, ns, nw, nout;
  double *p, *u, *M, *J[4], *w;
  long long int *iw, *piv, *nzr, *lp, *li, *up, *ui;
  double *lx, *ux;
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
  return FX_FORCE(s->arg, s->res, s->iw, s->w, 0);
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

static int fx_pset(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, realtype cj, void *data,
                   N_Vector t1, N_Vector t2, N_Vector t3) {
  fx_session *s = (fx_session *)data;
  long int n = s->nn, nx = s->nx, i, j, k;
  (void)yp; (void)rr; (void)t1; (void)t2; (void)t3;
  if (fx_call(1, s, t, NVD(yy), NVD(yy) + nx, s->J)) return -1;
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
    if (!(big > 0.0) || !isfinite(big)) return 1;              /* recoverable */
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
    for (i = k + 1; i < n; ++i)
      if (s->M[k * n + i] != 0.0) { s->li[cl] = i; s->lx[cl++] = s->M[k * n + i]; }
    for (i = 0; i < k; ++i)
      if (s->M[k * n + i] != 0.0) { s->ui[cu] = i; s->ux[cu++] = s->M[k * n + i]; }
  }
  s->lp[n] = cl; s->up[n] = cu;
  return 0;
}

static int fx_psol(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, N_Vector rv, N_Vector zv,
                   realtype cj, realtype delta, void *data, N_Vector tmp) {
  fx_session *s = (fx_session *)data;
  long int n = s->nn, k;
  long long int e;
  double *z = NVD(zv);
  (void)t; (void)yy; (void)yp; (void)rr; (void)cj; (void)delta; (void)tmp;
  memcpy(z, NVD(rv), sizeof(double) * n);
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

void *fx_new(long int nx, long int nz, long int np, long int nu, long int nq, double rtol,
             const double *atol, long int max_steps) {
  fx_session *s = (fx_session *)calloc(1, sizeof(fx_session));
  long long int a, r, i, w, sa = 0, sr = 0, si = 0, sw = 0;
  long int k;
  if (!s) return 0;
  s->nx = nx; s->nz = nz; s->nn = nx + nz; s->np = np; s->nu = nu; s->nq = nq;
  FX_DAE_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_JAC_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_QUAD_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
  sw = fx_max(sw, w);
  FX_FORCE_work(&a, &r, &i, &w); sa = fx_max(sa, a); sr = fx_max(sr, r); si = fx_max(si, i);
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

/* integrate to tout with the interval's inputs u; y, quadratures since the last reinit */
int fx_step(void *data, double tout, const double *u, double *y_out, double *q_out) {
  fx_session *s = (fx_session *)data;
  double t;
  s->msg[0] = 0;
  memcpy(s->u, u, sizeof(double) * s->nu);
  int flag = IDASetStopTime(s->mem, tout);
  if (!flag) flag = IDASolve(s->mem, tout, &t, s->yy, s->yp, 1 /* IDA_NORMAL */);
  if (flag < 0) return flag;
  memcpy(y_out, NVD(s->yy), sizeof(double) * s->nn);
  flag = IDAGetQuad(s->mem, &t, s->q);
  memcpy(q_out, NVD(s->q), sizeof(double) * s->nq);
  return flag < 0 ? flag : 0;
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
  free(s->lx); free(s->ux); free(s);
}
"""


def _sundials_paths() -> list[Path] | None:
    base = Path(ca.__file__).parent
    paths = [base / n for n in _SUNDIALS_LIBS]
    return paths if all(p.exists() for p in paths) else None


def live_library(dae_f: ca.Function, jac_f: ca.Function, quad_f: ca.Function,
                 force_f: ca.Function, cache_dir: str | None,
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
    cache_dir : str or None
        The compiled-library cache (default :func:`~maglevkit.models.compiled.cache_directory`).
    flags : tuple of str
        Compiler flags (the linker options for the IDAS library are added).
    """
    libs = _sundials_paths()
    if libs is None:
        return None
    cg = ca.CodeGenerator("maglevkit_flux_live", {"with_header": False})
    for f in (dae_f, jac_f, quad_f, force_f):
        cg.add(f)
    names = {"FX_DAE": dae_f.name(), "FX_JAC": jac_f.name(), "FX_QUAD": quad_f.name(),
             "FX_FORCE": force_f.name()}
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
    rtol : float
        Relative tolerance.
    atol : ndarray (nx + nz,)
        Absolute tolerances of the unknowns.
    max_num_steps : int
        IDAS step limit per call.
    """

    def __init__(self, library: Path, nx: int, nz: int, np_: int, nu: int, nq: int,
                 rtol: float, atol: np.ndarray, max_num_steps: int) -> None:
        lib = ctypes.CDLL(os.fspath(library))
        dp = ctypes.POINTER(ctypes.c_double)
        lib.fx_new.restype = ctypes.c_void_p
        lib.fx_new.argtypes = [ctypes.c_long] * 5 + [ctypes.c_double, dp, ctypes.c_long]
        lib.fx_reinit.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp, dp]
        lib.fx_step.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp, dp]
        lib.fx_message.restype = ctypes.c_char_p
        lib.fx_message.argtypes = [ctypes.c_void_p]
        lib.fx_free.argtypes = [ctypes.c_void_p]
        self._lib = lib
        self._dp = dp
        self.nx, self.nz, self.nq = nx, nz, nq
        atol = np.ascontiguousarray(atol, dtype=float)
        self._mem = lib.fx_new(nx, nz, np_, nu, nq, rtol, atol.ctypes.data_as(dp),
                               max_num_steps)
        if not self._mem:
            raise RuntimeError("IDAS could not be set up")
        self.y = np.empty(nx + nz)
        self.q = np.empty(nq)
        self._y_ptr = self.y.ctypes.data_as(dp)
        self._q_ptr = self.q.ctypes.data_as(dp)

    def _ptr(self, a: np.ndarray) -> Any:
        return a.ctypes.data_as(self._dp)

    def message(self) -> str:
        """The last message IDAS reported (empty if none)."""
        return (self._lib.fx_message(self._mem) or b"").decode(errors="replace")

    def reinit(self, t0: float, x0: np.ndarray, z0: np.ndarray, p: np.ndarray,
               u: np.ndarray) -> None:
        """Restart at normalised time ``t0``; RuntimeError (IDAS's message) on failure."""
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (x0, z0, p, u)]
        flag = self._lib.fx_reinit(self._mem, t0, *map(self._ptr, arrays))
        if flag < 0:
            raise RuntimeError(self.message() or f"IDAS initialisation flag {flag}")

    def step(self, tout: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Integrate to ``tout`` with interval inputs ``u``: (unknowns, quadratures since the
        last :meth:`reinit`), both arrays owned by this object (copy to keep)."""
        u = np.ascontiguousarray(u, dtype=float)
        flag = self._lib.fx_step(self._mem, tout, self._ptr(u), self._y_ptr, self._q_ptr)
        if flag < 0:
            raise RuntimeError(self.message() or f"IDAS flag {flag}")
        return self.y, self.q

    def __del__(self) -> None:
        mem, self._mem = getattr(self, "_mem", None), None
        if mem:
            self._lib.fx_free(mem)
