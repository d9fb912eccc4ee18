/* The reduced screen of the pruned mode search, compiled: qsplan.mechanics.solver.screen_kernel.
 *
 * The same decisions as the numpy reference qsplan.mechanics.solver.screen.screen_set (read that first:
 * this file transcribes it; the tests compare the two mode by mode).  For every breaking set B and every
 * rolling set R of the contacts A outside B, in lexicographic order:
 *
 *   kinematics (eqs. 13, 15, 24): v_n = 0 on A leaves x = x0 + Z u (Householder QR of N_A^T); the
 *     rolling rows T_R Z u = t_R fix u.  Rolling sets are visited depth first, one Gaussian elimination
 *     step (column pivoting) per level, the last two levels as 2 x 2 systems (Cramer), so that a
 *     p x p system costs O(1) per mode instead of an LU of its own; the product of the pivots is
 *     det(T_R Z) for the Hadamard ratio of the guard.  A breaking contact with v_n < -vmargin at the
 *     vertex rejects the mode.
 *   equilibrium (eqs. 16-17, 26, 28), for the few modes left: E_A c = rhs leaves c = c0 + N w (QR of
 *     E_A^T, done on the set's first such mode); the sliding contacts' c_t = -mu xi c_n (xi = sgn v_t,
 *     eq. 16) fix w by an n_S x n_S system: one LU gives the determinant for the guard and the solve.
 *     A Coulomb slack below -(force_rel * F) rejects the mode.
 *
 * Every other mode (ill-conditioned reduced systems, slip speeds too near zero to trust xi) is kept for
 * the reference test.  Plain CPython C API and the buffer protocol: no numpy headers at build time.  The
 * GIL is released while it computes, so threads run it in parallel.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    /* scene */
    int nc, dof;
    const double *M, *drive, *E, *rhs, *mu;
    double vmargin, slip, force_rel, red_sing, rhs_max;
    int coulomb;
    /* the current breaking set */
    int nA, b, r, nS, kin_ok, eq_ok; /* eq_ok: 0 not set up yet, 1 trusted, -1 not */
    int *A, *Bc, *rolling;
    double *Z, *x0, *TZ, *tx, *tznorm;   /* Z (dof, r), TZ (nA, r) */
    double *NB, *y0, c0norm2;            /* null basis (2nA, nS), particular force (2nA), its norm^2 */
    double *KS, *hS, *KSnorm;            /* per sign (xi = +1 then -1) and contact of A: the row c_t + mu xi c_n
                                          * of the sliding system in w (nS), its right-hand side, 1 / its norm */
    /* depth-first elimination: per level, rows (nA + b) x r coefficients and constants, the row chosen,
     * its pivot column, and the coordinate of u each free column stands for */
    int rows;
    double *coef, *cst, *inv_tznorm;
    int *path_i, *path_p, *colmap;
    /* work */
    double *qr, *q, *beta, *u, *K, *h, *y;
    unsigned char *code;
    /* output */
    unsigned char *out;
    size_t out_len, out_cap;
    long long n_kin, n_coul, n_total;
    int oom;
    int hot; /* the contact (position in A) whose slack rejected the last mode: checked first */
} Ctx;

/* Householder QR of X (m x n, row-major, m >= n): R in the upper triangle of X; reflector k in column k
 * of V (m x n, rows >= k) with beta[k] = 2 / |v_k|^2 (0: none), so that Q = H_0 H_1 ... H_{n-1}. */
static void house_qr(double *X, int m, int n, double *V, double *beta)
{
    for (int k = 0; k < n; k++) {
        double norm = 0.0;
        for (int i = k; i < m; i++)
            norm += X[i * n + k] * X[i * n + k];
        norm = sqrt(norm);
        beta[k] = 0.0;
        if (norm == 0.0)
            continue;
        double alpha = X[k * n + k] >= 0 ? -norm : norm, vv = 0.0;
        for (int i = k; i < m; i++) {
            V[i * n + k] = X[i * n + k] - (i == k ? alpha : 0.0);
            vv += V[i * n + k] * V[i * n + k];
        }
        if (vv == 0.0)
            continue;
        beta[k] = 2.0 / vv;
        for (int j = k; j < n; j++) {
            double s = 0.0;
            for (int i = k; i < m; i++)
                s += V[i * n + k] * X[i * n + j];
            s *= beta[k];
            for (int i = k; i < m; i++)
                X[i * n + j] -= s * V[i * n + k];
        }
    }
}

/* x <- Q x for the Q of house_qr (m-vector): only the columns of Q that are needed are ever formed. */
static void apply_q(const double *V, const double *beta, int m, int n, double *x)
{
    for (int k = n - 1; k >= 0; k--) {
        if (beta[k] == 0.0)
            continue;
        double s = 0.0;
        for (int i = k; i < m; i++)
            s += V[i * n + k] * x[i];
        s *= beta[k];
        for (int i = k; i < m; i++)
            x[i] -= s * V[i * n + k];
    }
}

/* Hadamard ratio of the rows of X^T (the columns of X, m x n) from its R: prod |R_ii| / prod ||col_i||. */
static double gram_ratio(const double *R, const double *X0, int m, int n)
{
    double logr = 0.0;
    for (int i = 0; i < n; i++) {
        double nn = 0.0;
        for (int l = 0; l < m; l++)
            nn += X0[l * n + i] * X0[l * n + i];
        double rii = fabs(R[i * n + i]);
        if (rii == 0.0 || nn == 0.0)
            return 0.0;
        logr += log(rii) - 0.5 * log(nn);
    }
    return exp(logr);
}

/* x = Q1 R^{-T} b, the least-norm solution of (Q1 R)^T x = b (R n x n in X, m x n). */
static void particular(const double *X, const double *V, const double *beta, int m, int n, const double *b, double *x)
{
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++)
            s -= X[k * n + i] * x[k];
        x[i] = s / X[i * n + i];
    }
    for (int l = n; l < m; l++)
        x[l] = 0.0;
    apply_q(V, beta, m, n, x);
}

/* Columns n .. m-1 of Q (an orthonormal basis of the null space of X^T) into B (m x (m - n), row-major). */
static void null_basis(const double *V, const double *beta, int m, int n, double *B, double *x)
{
    for (int q = 0; q < m - n; q++) {
        for (int l = 0; l < m; l++)
            x[l] = l == n + q;
        apply_q(V, beta, m, n, x);
        for (int l = 0; l < m; l++)
            B[l * (m - n) + q] = x[l];
    }
}

static int emit(Ctx *c)
{
    if (c->out_len + (size_t)c->nc > c->out_cap) {
        size_t cap = c->out_cap ? 2 * c->out_cap : (size_t)c->nc * 4096;
        unsigned char *p = realloc(c->out, cap);
        if (!p) {
            c->oom = 1;
            return -1;
        }
        c->out = p;
        c->out_cap = cap;
    }
    for (int s = 0; s < c->nA; s++)
        c->code[c->A[s]] = c->rolling[s] ? 1 : 2;
    memcpy(c->out + c->out_len, c->code, (size_t)c->nc);
    c->out_len += (size_t)c->nc;
    return 0;
}

/* Set up the reduced kinematics (x0, Z, TZ) and equilibrium (c0, N) of the breaking set in c->code. */
static void setup_set(Ctx *c)
{
    int nc = c->nc, dof = c->dof, nA = 0, b = 0;
    for (int i = 0; i < nc; i++) {
        if (c->code[i] == 0)
            c->Bc[b++] = i;
        else
            c->A[nA++] = i;
    }
    c->nA = nA;
    c->b = b;
    c->r = dof - nA;
    c->nS = nA - c->r;
    int r = c->r;
    c->eq_ok = 0;
    c->hot = 0;
    /* kinematics: QR of N_A^T (dof x nA) */
    double *X = c->qr, *Q = c->q;
    for (int l = 0; l < dof; l++)
        for (int j = 0; j < nA; j++)
            X[l * nA + j] = c->M[c->A[j] * dof + l];
    double *X0 = c->K; /* a copy for the row norms */
    memcpy(X0, X, sizeof(double) * dof * nA);
    house_qr(X, dof, nA, Q, c->beta);
    c->kin_ok = nA == 0 || gram_ratio(X, X0, dof, nA) >= c->red_sing;
    if (!c->kin_ok)
        return;
    double *dnA = c->y;
    for (int j = 0; j < nA; j++)
        dnA[j] = c->drive[c->A[j]];
    particular(X, Q, c->beta, dof, nA, dnA, c->x0);
    null_basis(Q, c->beta, dof, nA, c->Z, c->h);
    for (int s = 0; s < nA; s++) {
        const double *T = c->M + (size_t)(nc + c->A[s]) * dof;
        double t0 = 0.0, nn = 0.0;
        for (int l = 0; l < dof; l++)
            t0 += T[l] * c->x0[l];
        c->tx[s] = c->drive[nc + c->A[s]] - t0;
        for (int q = 0; q < r; q++) {
            double acc = 0.0;
            for (int l = 0; l < dof; l++)
                acc += T[l] * c->Z[l * r + q];
            c->TZ[s * r + q] = acc;
            nn += acc * acc;
        }
        c->tznorm[s] = sqrt(nn);
    }
    /* level 0 of the elimination: v_t = TZ u - tx (candidates), v_n = NBZ u + nbx (B) */
    double *coef = c->coef, *cst = c->cst;
    for (int s = 0; s < nA; s++) {
        for (int q = 0; q < r; q++)
            coef[s * r + q] = c->TZ[s * r + q];
        cst[s] = -c->tx[s];
    }
    for (int k = 0; k < b; k++) {
        const double *N = c->M + (size_t)c->Bc[k] * dof;
        double nx = 0.0;
        for (int l = 0; l < dof; l++)
            nx += N[l] * c->x0[l];
        for (int q = 0; q < r; q++) {
            double acc = 0.0;
            for (int l = 0; l < dof; l++)
                acc += N[l] * c->Z[l * r + q];
            coef[(nA + k) * r + q] = acc;
        }
        cst[nA + k] = nx - c->drive[c->Bc[k]];
    }
    c->rows = nA + b;
    for (int q = 0; q < r; q++)
        c->colmap[q] = q;
    for (int s = 0; s < nA; s++)
        c->inv_tznorm[s] = c->tznorm[s] > 0 ? 1.0 / c->tznorm[s] : 0.0;
}

/* The reduced equilibrium of the set (c0, N), on its first mode that reaches eq. (28): most sets of
 * the small scenes have none.  QR of E_A^T (2nA x dof), forces ordered [c_n(A); c_t(A)]. */
static void setup_equilibrium(Ctx *c)
{
    int nc = c->nc, dof = c->dof, nA = c->nA, m2 = 2 * nA;
    double *X = c->qr, *X0 = c->K, *Q2 = c->q, *tmp = c->h;
    c->eq_ok = -1;
    for (int j = 0; j < m2; j++) {
        int row = j < nA ? c->A[j] : nc + c->A[j - nA];
        for (int l = 0; l < dof; l++)
            X[j * dof + l] = c->E[(size_t)row * dof + l];
    }
    memcpy(X0, X, sizeof(double) * m2 * dof);
    house_qr(X, m2, dof, Q2, c->beta);
    if (gram_ratio(X, X0, m2, dof) < c->red_sing)
        return;
    particular(X, Q2, c->beta, m2, dof, c->rhs, c->y0);
    c->c0norm2 = 0.0;
    for (int j = 0; j < m2; j++)
        c->c0norm2 += c->y0[j] * c->y0[j];
    null_basis(Q2, c->beta, m2, dof, c->NB, tmp);
    int nS = c->nS;
    for (int sg = 0; sg < 2; sg++)
        for (int s = 0; s < nA; s++) {
            double mx = c->mu[c->A[s]] * (sg == 0 ? 1.0 : -1.0), nn = 0.0;
            const double *Nn = c->NB + (size_t)s * nS, *Nt = c->NB + (size_t)(nA + s) * nS;
            double *row = c->KS + ((size_t)sg * nA + s) * nS;
            for (int q = 0; q < nS; q++) {
                row[q] = Nt[q] + mx * Nn[q];
                nn += row[q] * row[q];
            }
            c->hS[sg * nA + s] = -(c->y0[nA + s] + mx * c->y0[s]);
            c->KSnorm[sg * nA + s] = nn > 0 ? 1.0 / sqrt(nn) : 0.0;
        }
    c->eq_ok = 1;
}

/* The equilibrium and Coulomb screen of the mode at vertex u: 1 to prune, 0 to keep. */
static int coulomb_prunes(Ctx *c, const double *u)
{
    int nA = c->nA, r = c->r, nS = c->nS;
    double *K = c->K, *h = c->h;
    int k = 0;
    double ratio = 1.0;
    for (int s = 0; s < nA; s++) {
        if (c->rolling[s])
            continue;
        double vt = -c->tx[s];
        for (int q = 0; q < r; q++)
            vt += c->TZ[s * r + q] * u[q];
        if (!(fabs(vt) > c->slip))
            return 0; /* xi (eq. 16) not certain: the reference decides */
        int at = (vt <= 0) * nA + s; /* xi = +1 rows first */
        if (c->KSnorm[at] == 0.0)
            return 0;
        memcpy(K + (size_t)k * nS, c->KS + (size_t)at * nS, sizeof(double) * nS);
        h[k] = c->hS[at];
        ratio *= c->KSnorm[at];
        k++;
    }
    /* one LU with partial pivoting: the determinant for the guard, then the solve.  Rows are swapped by
     * pointer; each elimination updates one row from another (distinct rows: restrict, vectorised). */
    double *dinv = c->y; /* 1 / pivot (c->y: free during the screen) */
    double *rowp[nS > 0 ? nS : 1], hh[nS > 0 ? nS : 1];
    for (int i = 0; i < nS; i++) {
        rowp[i] = K + (size_t)i * nS;
        hh[i] = h[i];
    }
    for (int j = 0; j < nS; j++) {
        int p = j;
        double best = fabs(rowp[j][j]);
        for (int i = j + 1; i < nS; i++) { /* the first largest, as before; selects, not branches (the
                                             * pivot's row is unpredictable) */
            double a = fabs(rowp[i][j]);
            int gt = a > best;
            best = gt ? a : best;
            p = gt ? i : p;
        }
        if (best == 0.0)
            return 0;
        double *t = rowp[j], th = hh[j]; /* swapped unconditionally (p == j: a no-op) */
        rowp[j] = rowp[p];
        rowp[p] = t;
        hh[j] = hh[p];
        hh[p] = th;
        const double *restrict pj = rowp[j];
        double inv = 1.0 / pj[j], hj = hh[j];
        dinv[j] = inv;
        ratio *= best;
        for (int i = j + 1; i < nS; i++) {
            double *restrict pi = rowp[i];
            double f = pi[j] * inv;
            for (int q = j + 1; q < nS; q++)
                pi[q] -= f * pj[q];
            hh[i] -= f * hj;
        }
    }
    if (!(ratio >= c->red_sing))
        return 0;
    double *w = c->u + r; /* after u */
    for (int i = nS - 1; i >= 0; i--) { /* the pivots' inverses: no division on the chain of dependent steps */
        const double *pi = rowp[i];
        double s = hh[i];
        for (int q = i + 1; q < nS; q++)
            s -= pi[q] * w[q];
        w[i] = s * dinv[i];
    }
    /* ||c||_2^2 = ||c0||^2 + ||w||^2 (c0, the least-norm force, is orthogonal to N's columns) bounds F:
     * a slack below -force_rel * Fup prunes at once (2: room for rounding; the exact test would too).
     * Whether some slack falls below it does not depend on the order the contacts are checked in: the
     * contact that rejected the last mode goes first (neighbouring modes mostly fail at the same one). */
    double ww = c->c0norm2;
    for (int q = 0; q < nS; q++)
        ww += w[q] * w[q];
    double Fup = 2.0 * fmax(c->rhs_max, sqrt(ww)), early = -c->force_rel * Fup;
    double F = c->rhs_max, worst = INFINITY;
    for (int k = -1; k < nA; k++) {
        int s = k < 0 ? c->hot : k;
        if (k == c->hot)
            continue;
        double cn = c->y0[s];
        const double *Nn = c->NB + (size_t)s * nS, *Nt = c->NB + (size_t)(nA + s) * nS;
        for (int q = 0; q < nS; q++)
            cn += Nn[q] * w[q];
        if (fabs(cn) > F)
            F = fabs(cn);
        if (cn < worst)
            worst = cn;
        if (c->rolling[s]) { /* eq. (28); a sliding contact's c_t is -mu xi c_n by construction, unused */
            double ct = c->y0[nA + s];
            for (int q = 0; q < nS; q++)
                ct += Nt[q] * w[q];
            double m = c->mu[c->A[s]] * cn;
            if (fabs(ct) > F)
                F = fabs(ct);
            if (m + ct < worst)
                worst = m + ct;
            if (m - ct < worst)
                worst = m - ct;
        }
        if (worst < early) {
            c->hot = s;
            return 1;
        }
    }
    return F > 0 && worst < -c->force_rel * F;
}

/* u at a leaf, by back-substitution along the path from level top down: the free coordinates of
 * level top + 1 are already in u. */
static void vertex(Ctx *c, int top, double *u)
{
    int r = c->r, rows = c->rows;
    for (int j = top; j >= 0; j--) {
        const double *pr = c->coef + ((size_t)j * rows + c->path_i[j]) * r;
        const int *cm = c->colmap + (size_t)j * r;
        int p = c->path_p[j], f = r - j;
        double s = c->cst[(size_t)j * rows + c->path_i[j]];
        for (int q = 0; q < f; q++)
            if (q != p)
                s += pr[q] * u[cm[q]];
        u[cm[p]] = -s / pr[p];
    }
}

/* The kept mode below the current path: equilibrium screen, else emitted.  u: its vertex. */
static int survivor(Ctx *c, const double *u)
{
    if (c->eq_ok == 0 && c->coulomb)
        setup_equilibrium(c);
    if (c->eq_ok == 1 && coulomb_prunes(c, u)) {
        c->n_coul++;
        return 0;
    }
    return emit(c);
}

/* Every rolling set below level j, unscreened (the reduced system is not trusted there). */
static int unscreened(Ctx *c, int j, int last)
{
    int f = c->r - j;
    if (f == 0) {
        c->n_total++;
        return emit(c);
    }
    for (int i = last + 1; i <= c->nA - f; i++) {
        c->rolling[i] = 1;
        int rc = unscreened(c, j + 1, i);
        c->rolling[i] = 0;
        if (rc)
            return rc;
    }
    return 0;
}

/* Depth-first over rolling sets: level j has j rolling rows eliminated; its children are the rows > last. */
static int descend(Ctx *c, int j, int last, double ratio)
{
    int nA = c->nA, b = c->b, r = c->r, f = r - j, rows = c->rows;
    double *coef = c->coef + (size_t)j * rows * r, *cst = c->cst + (size_t)j * rows;
    if (f == 0) { /* no rolling contact: one mode, x = x0 */
        c->n_total++;
        for (int k = 0; k < b; k++)
            if (cst[nA + k] < -c->vmargin) {
                c->n_kin++;
                return 0;
            }
        return survivor(c, c->u);
    }
    if (f == 1) { /* the leaves: row i fixes the last coordinate t; v_n on B is affine in t (eq. 15) */
        const double *cB = coef + (size_t)nA * r, *dB = cst + nA;
        double lo = -INFINITY, hi = INFINITY; /* v_n >= -vmargin on all of B <=> lo <= t <= hi */
        for (int k = 0; k < b; k++) {
            double ck = cB[(size_t)k * r], dk = dB[k] + c->vmargin;
            double tk = -dk / ck;
            if (ck > 0)
                lo = tk > lo ? tk : lo;
            else if (ck < 0)
                hi = tk < hi ? tk : hi;
            else if (dk < 0)
                lo = INFINITY; /* every leaf below penetrates */
        }
        c->n_total += nA - (last + 1);
        for (int i = last + 1; i < nA; i++) {
            double pv = coef[(size_t)i * r], rat = ratio * fabs(pv) * c->inv_tznorm[i];
            if (!(rat >= c->red_sing)) { /* not trusted (or singular): the reference decides */
                c->rolling[i] = 1;
                int rc = emit(c);
                c->rolling[i] = 0;
                if (rc)
                    return rc;
                continue;
            }
            double t = -cst[i] / pv;
            if (!(t >= lo && t <= hi)) {
                c->n_kin++;
                continue;
            }
            c->rolling[i] = 1;
            c->u[c->colmap[(size_t)j * r]] = t;
            vertex(c, j - 1, c->u);
            int rc = survivor(c, c->u);
            c->rolling[i] = 0;
            if (rc)
                return rc;
        }
        return 0;
    }
    if (f == 2) { /* the leaves in pairs (i, l): row l cuts line i (row i = 0) at its vertex */
        const double *cB = coef + (size_t)nA * r, *dB = cst + nA;
        const int *cm = c->colmap + (size_t)j * r;
        double vm = c->vmargin;
        for (int i = last + 1; i < nA - 1; i++) {
            double a0 = coef[(size_t)i * r], a1 = coef[(size_t)i * r + 1], ci = cst[i];
            double ri = ratio * c->inv_tznorm[i], aa = a0 * a0 + a1 * a1;
            /* line i: t = p + s d, p = -ci a / |a|^2, d = (-a1, a0); v_n >= -vmargin on all of B (eq. 15)
             * <=> lo <= s <= hi, as at f == 1.  (|a| = 0: every pair below is singular, emitted untested.) */
            double p0 = aa > 0 ? -ci * a0 / aa : 0.0, p1 = aa > 0 ? -ci * a1 / aa : 0.0, lo = -INFINITY, hi = INFINITY;
            for (int k = 0; k < b; k++) {
                double c0 = cB[(size_t)k * r], c1 = cB[(size_t)k * r + 1];
                double ck = a0 * c1 - a1 * c0, dk = dB[k] + vm + c0 * p0 + c1 * p1, tk = -dk / ck;
                if (ck > 0)
                    lo = tk > lo ? tk : lo;
                else if (ck < 0)
                    hi = tk < hi ? tk : hi;
                else if (dk < 0)
                    lo = INFINITY; /* every vertex on the line penetrates */
            }
            c->rolling[i] = 1;
            c->n_total += nA - 1 - i;
            if (!(lo <= hi)) { /* no vertex on line i keeps B out of penetration: only the untrusted pairs stay */
                for (int l = i + 1; l < nA; l++) {
                    double det = a0 * coef[(size_t)l * r + 1] - a1 * coef[(size_t)l * r];
                    if (ri * fabs(det) * c->inv_tznorm[l] >= c->red_sing) {
                        c->n_kin++;
                        continue;
                    }
                    c->rolling[l] = 1;
                    int rc = emit(c);
                    c->rolling[l] = 0;
                    if (rc) {
                        c->rolling[i] = 0;
                        return rc;
                    }
                }
                c->rolling[i] = 0;
                continue;
            }
            for (int l = i + 1; l < nA; l++) {
                double b0 = coef[(size_t)l * r], b1 = coef[(size_t)l * r + 1], cl = cst[l];
                double det = a0 * b1 - a1 * b0, rat = ri * fabs(det) * c->inv_tznorm[l];
                int rc = 0;
                if (!(rat >= c->red_sing)) { /* not trusted (or singular): the reference decides */
                    c->rolling[l] = 1;
                    rc = emit(c);
                    c->rolling[l] = 0;
                } else {
                    double sv = -(b0 * p0 + b1 * p1 + cl) / det; /* b.(p + s d) + cl = 0, b.d = det */
                    if (sv < lo || sv > hi) {
                        c->n_kin++;
                    } else {
                        c->rolling[l] = 1;
                        c->u[cm[0]] = p0 - sv * a1;
                        c->u[cm[1]] = p1 + sv * a0;
                        vertex(c, j - 1, c->u);
                        rc = survivor(c, c->u);
                        c->rolling[l] = 0;
                    }
                }
                if (rc) {
                    c->rolling[i] = 0;
                    return rc;
                }
            }
            c->rolling[i] = 0;
        }
        return 0;
    }
    const int *cm = c->colmap + (size_t)j * r;
    int *ncm = c->colmap + (size_t)(j + 1) * r;
    for (int i = last + 1; i <= nA - f; i++) {
        const double *pr = coef + (size_t)i * r;
        int p = 0;
        double best = fabs(pr[0]);
        for (int q = 1; q < f; q++)
            if (fabs(pr[q]) > best) {
                best = fabs(pr[q]);
                p = q;
            }
        int rc;
        c->rolling[i] = 1;
        if (best == 0.0 || c->tznorm[i] == 0.0) { /* singular below: the reference decides */
            rc = unscreened(c, j + 1, i);
        } else { /* eliminate free column p with row i from the rows the subtree still needs */
            double inv = 1.0 / pr[p], *nco = coef + (size_t)rows * r, *ncs = cst + rows;
            for (int l = i + 1; l < rows; l++) {
                const double *src = coef + (size_t)l * r;
                double *dst = nco + (size_t)l * r, fac = src[p] * inv;
                for (int q = 0; q < f; q++) /* column p vanishes: the last column moves into its place */
                    dst[q] = src[q] - fac * pr[q];
                dst[p] = dst[f - 1];
                ncs[l] = cst[l] - fac * cst[i];
            }
            for (int q = 0; q < f - 1; q++)
                ncm[q] = cm[q == p ? f - 1 : q];
            c->path_i[j] = i;
            c->path_p[j] = p;
            rc = descend(c, j + 1, i, ratio * best * c->inv_tznorm[i]);
        }
        c->rolling[i] = 0;
        if (rc)
            return rc;
    }
    return 0;
}

static int run(Ctx *c, const unsigned char *masks, Py_ssize_t n_sets)
{
    for (Py_ssize_t s = 0; s < n_sets; s++) {
        const unsigned char *mask = masks + s * c->nc;
        int nA = 0;
        for (int i = 0; i < c->nc; i++) {
            c->code[i] = mask[i] ? 0 : 2;
            nA += !mask[i];
        }
        int r = c->dof - nA;
        if (r < 0 || r > nA)
            continue; /* no mode has this breaking set (eq. 29) */
        memset(c->rolling, 0, sizeof(int) * c->nc);
        setup_set(c);
        int rc = c->kin_ok ? descend(c, 0, -1, 1.0) : unscreened(c, 0, -1);
        if (rc)
            return rc;
    }
    return 0;
}

static PyObject *screen(PyObject *self, PyObject *args)
{
    (void)self;
    Py_buffer M, drive, E, rhs, mu, masks;
    int nc, dof, coulomb;
    double vmargin, slip, force_rel, red_sing;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*iiddddp", &M, &drive, &E, &rhs, &mu, &masks, &nc, &dof, &vmargin,
                          &slip, &force_rel, &red_sing, &coulomb))
        return NULL;
    PyObject *result = NULL;
    Ctx c;
    memset(&c, 0, sizeof c);
    size_t d = sizeof(double);
    if (nc < 1 || dof < 1 || M.len != (Py_ssize_t)(2 * nc * dof * d) || E.len != M.len ||
        drive.len != (Py_ssize_t)(2 * nc * d) || rhs.len != (Py_ssize_t)(dof * d) || mu.len != (Py_ssize_t)(nc * d) ||
        masks.len % nc != 0) {
        PyErr_SetString(PyExc_ValueError, "screen: arrays of the wrong size for n_c and dof");
        goto done;
    }
    c.nc = nc;
    c.dof = dof;
    c.M = M.buf;
    c.drive = drive.buf;
    c.E = E.buf;
    c.rhs = rhs.buf;
    c.mu = mu.buf;
    c.vmargin = vmargin;
    c.slip = slip;
    c.force_rel = force_rel;
    c.red_sing = red_sing;
    c.coulomb = coulomb;
    for (int l = 0; l < dof; l++)
        if (fabs(c.rhs[l]) > c.rhs_max)
            c.rhs_max = fabs(c.rhs[l]);
    c.rows = nc;
    int big = 2 * nc > dof ? 2 * nc : dof, mat = 2 * nc * dof > nc * nc ? 2 * nc * dof : nc * nc;
    c.A = malloc(sizeof(int) * nc);
    c.Bc = malloc(sizeof(int) * nc);
    c.rolling = malloc(sizeof(int) * nc);
    c.code = malloc(nc);
    c.Z = malloc(d * dof * dof);
    c.x0 = malloc(d * dof);
    c.TZ = malloc(d * nc * dof);
    c.tx = malloc(d * nc);
    c.tznorm = malloc(d * nc);
    c.NB = malloc(d * 2 * nc * 2 * nc);
    c.KS = malloc(d * 2 * nc * 2 * nc);
    c.hS = malloc(d * 2 * nc);
    c.KSnorm = malloc(d * 2 * nc);
    c.y0 = malloc(d * 2 * nc);
    c.coef = malloc(d * (dof + 1) * nc * dof);
    c.cst = malloc(d * (dof + 1) * nc);
    c.inv_tznorm = malloc(d * nc);
    c.path_i = malloc(sizeof(int) * (dof + 1));
    c.path_p = malloc(sizeof(int) * (dof + 1));
    c.colmap = malloc(sizeof(int) * (dof + 1) * dof);
    c.qr = malloc(d * 2 * nc * dof);
    c.q = malloc(d * big * big);
    c.beta = malloc(d * big);
    c.u = malloc(d * (dof + 2 * nc));
    c.K = malloc(d * mat);
    c.h = malloc(d * (dof + 2 * nc));
    c.y = malloc(d * (dof + 2 * nc));
    if (!(c.A && c.Bc && c.rolling && c.code && c.Z && c.x0 && c.TZ && c.tx && c.tznorm && c.NB && c.KS && c.hS && c.KSnorm && c.y0 &&
          c.coef && c.cst && c.inv_tznorm && c.path_i && c.path_p && c.colmap && c.qr && c.q && c.beta && c.u && c.K && c.h && c.y)) {
        PyErr_NoMemory();
        goto done;
    }
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = run(&c, masks.buf, masks.len / nc);
    Py_END_ALLOW_THREADS
    if (rc || c.oom) {
        PyErr_NoMemory();
        goto done;
    }
    PyObject *codes = PyBytes_FromStringAndSize((const char *)c.out, (Py_ssize_t)c.out_len);
    if (codes)
        result = Py_BuildValue("(NLLL)", codes, c.n_kin, c.n_coul, c.n_total);
done:
    free(c.A); free(c.Bc); free(c.rolling); free(c.code); free(c.Z); free(c.x0); free(c.TZ);
    free(c.tx); free(c.tznorm); free(c.NB); free(c.KS); free(c.hS); free(c.KSnorm); free(c.y0); free(c.coef); free(c.cst); free(c.inv_tznorm); free(c.path_i); free(c.path_p); free(c.colmap); free(c.qr); free(c.q); free(c.beta);
    free(c.u); free(c.K); free(c.h); free(c.y); free(c.out);
    PyBuffer_Release(&M); PyBuffer_Release(&drive); PyBuffer_Release(&E);
    PyBuffer_Release(&rhs); PyBuffer_Release(&mu); PyBuffer_Release(&masks);
    return result;
}

/* ---- The equilibrium relaxation of breaking sets (breaking_sets.py), one small dense simplex per set ----
 *
 * Every contact i outside the breaking set carries a force in its widened cone, written with nonnegative
 * columns: c_i = base_i + sum_j z_j dir_j (rays (1, +-mu) unbounded; for mu < 1 a segment column bounded
 * by ub_j).  The equilibrium rows read G z = r, r = b - sum_i shift_i (shift_i = E_i base_i).  Phase 1 of
 * a bounded primal simplex (artificials on every row, dense basis inverse, Dantzig pricing, Bland's rule
 * after a run of degenerate pivots) decides it.  The verdict never trusts the tableau:
 *   feasible (1): the basic solution, recomputed from the columns, balances r within feas_tol (the force
 *     is returned: a witness);
 *   infeasible (0): y, the last simplex multipliers, is checked as a Farkas certificate from the data:
 *     M = y.r - sum over bounded columns of max(0, y.G_j) ub_j must exceed cert_margin * |y|_1 * max(1,
 *     |r|_inf), and every balancing z then has sum_j viol_j z_j >= M over the unbounded columns
 *     (viol_j = max(0, y.G_j)), so it needs ray coefficients summing to M / max viol_j at least: proven
 *     when that is >= proof_ratio (or no violation at all);
 *   unknown (-1): anything else (iteration cap, a weak certificate): the caller decides another way. */
typedef struct {
    int m, N, nc, maxit;
    const double *G, *ub, *gnorm, *dir, *shift, *base, *b;
    const int *owner;
    double dtol, ptol, feas_tol, cert_margin, proof_ratio;
    /* work */
    int *cols, *state, *bv;
    double *Binv, *xB, *cB, *y, *alpha, *r, *z;
} Relax;

static double dotm(const double *a, const double *b, int m)
{
    double s = 0.0;
    for (int l = 0; l < m; l++)
        s += a[l] * b[l];
    return s;
}

static int relax_one(Relax *p, const unsigned char *mask, double *force)
{
    int m = p->m, na = 0;
    double *Binv = p->Binv, *xB = p->xB, *cB = p->cB, *y = p->y, *alpha = p->alpha, *r = p->r;
    for (int j = 0; j < p->N; j++)
        if (!mask[p->owner[j]]) {
            p->cols[na++] = j;
            p->state[j] = 0; /* 0 at its lower bound, 1 at its upper bound, 2 basic */
        }
    memcpy(r, p->b, sizeof(double) * m);
    for (int i = 0; i < p->nc; i++)
        if (!mask[i])
            for (int l = 0; l < m; l++)
                r[l] -= p->shift[(size_t)i * m + l];
    memset(Binv, 0, sizeof(double) * m * m);
    for (int k = 0; k < m; k++) {
        Binv[k * m + k] = r[k] >= 0 ? 1.0 : -1.0; /* artificial k: column sign(r_k) e_k, value |r_k| */
        xB[k] = fabs(r[k]);
        p->bv[k] = -1;
        cB[k] = 1.0;
    }
    int it, degenerate = 0, bland = 0;
    for (it = 0; it < p->maxit; it++) {
        for (int l = 0; l < m; l++)
            y[l] = 0.0;
        for (int k = 0; k < m; k++)
            if (cB[k] != 0.0)
                for (int l = 0; l < m; l++)
                    y[l] += cB[k] * Binv[k * m + l];
        int enter = -1;
        double best = 0.0;
        for (int q = 0; q < na; q++) {
            int j = p->cols[q];
            if (p->state[j] == 2 || p->gnorm[j] == 0.0)
                continue; /* basic, or a column with no equilibrium row (it changes nothing) */
            double yg = dotm(y, p->G + (size_t)j * m, m);
            double gain = (p->state[j] == 0 ? yg : -yg) / p->gnorm[j]; /* objective decrease per unit step */
            if (gain > p->dtol && (bland ? enter < 0 : gain > best)) {
                best = gain;
                enter = j;
            }
        }
        if (enter < 0)
            break;
        const double *g = p->G + (size_t)enter * m;
        for (int k = 0; k < m; k++)
            alpha[k] = dotm(Binv + (size_t)k * m, g, m);
        double sgn = p->state[enter] == 0 ? 1.0 : -1.0, theta = p->ub[enter];
        int leave = -1, to_upper = 0;
        for (int k = 0; k < m; k++) {
            double a = sgn * alpha[k], t;
            if (a > p->ptol) {
                t = xB[k] > 0 ? xB[k] / a : 0.0;
                if (t < theta) {
                    theta = t;
                    leave = k;
                    to_upper = 0;
                }
            } else if (a < -p->ptol && p->bv[k] >= 0 && isfinite(p->ub[p->bv[k]])) {
                double room = p->ub[p->bv[k]] - xB[k];
                t = room > 0 ? room / -a : 0.0;
                if (t < theta) {
                    theta = t;
                    leave = k;
                    to_upper = 1;
                }
            }
        }
        if (!isfinite(theta))
            return -1; /* unbounded: impossible in phase 1 but for rounding */
        for (int k = 0; k < m; k++)
            xB[k] -= sgn * theta * alpha[k];
        if (leave < 0) { /* the entering column reaches its other bound first */
            p->state[enter] = 1 - p->state[enter];
            continue;
        }
        int out = p->bv[leave];
        if (out >= 0)
            p->state[out] = to_upper;
        xB[leave] = p->state[enter] == 0 ? theta : p->ub[enter] - theta;
        p->bv[leave] = enter;
        cB[leave] = 0.0;
        p->state[enter] = 2;
        double *row = Binv + (size_t)leave * m, inv = 1.0 / alpha[leave];
        for (int l = 0; l < m; l++)
            row[l] *= inv;
        for (int k = 0; k < m; k++) {
            double f = alpha[k];
            if (k == leave || f == 0.0)
                continue;
            double *dst = Binv + (size_t)k * m;
            for (int l = 0; l < m; l++)
                dst[l] -= f * row[l];
        }
        degenerate = theta <= p->ptol ? degenerate + 1 : 0;
        if (degenerate > m)
            bland = 1;
    }
    if (it >= p->maxit)
        return -1;
    /* the verdict from the data: the basic solution's residual, else y as a Farkas certificate */
    double *z = p->z, res = 0.0;
    for (int q = 0; q < na; q++) {
        int j = p->cols[q];
        z[j] = p->state[j] == 1 ? p->ub[j] : 0.0;
    }
    for (int k = 0; k < m; k++)
        if (p->bv[k] >= 0) {
            double v = xB[k] > 0 ? xB[k] : 0.0, u = p->ub[p->bv[k]];
            z[p->bv[k]] = v < u ? v : u;
        }
    for (int l = 0; l < m; l++) {
        double s = r[l];
        for (int q = 0; q < na; q++) {
            int j = p->cols[q];
            s -= p->G[(size_t)j * m + l] * z[j];
        }
        res = fmax(res, fabs(s));
    }
    if (res <= p->feas_tol) {
        for (int i = 0; i < p->nc; i++) {
            force[2 * i] = mask[i] ? 0.0 : p->base[2 * i];
            force[2 * i + 1] = mask[i] ? 0.0 : p->base[2 * i + 1];
        }
        for (int q = 0; q < na; q++) {
            int j = p->cols[q], i = p->owner[j];
            force[2 * i] += z[j] * p->dir[2 * j];
            force[2 * i + 1] += z[j] * p->dir[2 * j + 1];
        }
        return 1;
    }
    double M = dotm(y, r, m), viol = 0.0, ynorm = 0.0, rmax = 1.0;
    for (int l = 0; l < m; l++) {
        ynorm += fabs(y[l]);
        rmax = fmax(rmax, fabs(r[l]));
    }
    for (int q = 0; q < na; q++) {
        int j = p->cols[q];
        double yg = dotm(y, p->G + (size_t)j * m, m);
        if (yg <= 0)
            continue;
        if (isfinite(p->ub[j]))
            M -= yg * p->ub[j];
        else
            viol = fmax(viol, yg);
    }
    if (M > p->cert_margin * ynorm * rmax && (viol == 0.0 || M >= p->proof_ratio * viol))
        return 0;
    return -1;
}

static PyObject *relax(PyObject *self, PyObject *args)
{
    (void)self;
    Py_buffer G, ub, gnorm, owner, dir, shift, base, b, masks;
    Relax p;
    memset(&p, 0, sizeof p);
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*y*iiiiddddd", &G, &ub, &gnorm, &owner, &dir, &shift, &base, &b,
                          &masks, &p.nc, &p.m, &p.N, &p.maxit, &p.dtol, &p.ptol, &p.feas_tol, &p.cert_margin,
                          &p.proof_ratio))
        return NULL;
    PyObject *result = NULL;
    size_t d = sizeof(double);
    int nc = p.nc, m = p.m, N = p.N;
    if (nc < 1 || m < 1 || N < 0 || G.len != (Py_ssize_t)(N * m * d) || ub.len != (Py_ssize_t)(N * d) ||
        gnorm.len != ub.len || owner.len != (Py_ssize_t)(N * sizeof(int)) || dir.len != (Py_ssize_t)(2 * N * d) ||
        shift.len != (Py_ssize_t)(nc * m * d) || base.len != (Py_ssize_t)(2 * nc * d) || b.len != (Py_ssize_t)(m * d) ||
        masks.len % nc != 0) {
        PyErr_SetString(PyExc_ValueError, "relax: arrays of the wrong size for n_c, rows and columns");
        goto done;
    }
    for (int j = 0; j < N; j++)
        if (((const int *)owner.buf)[j] < 0 || ((const int *)owner.buf)[j] >= nc) {
            PyErr_SetString(PyExc_ValueError, "relax: a column's contact out of range");
            goto done;
        }
    p.G = G.buf;
    p.ub = ub.buf;
    p.gnorm = gnorm.buf;
    p.owner = owner.buf;
    p.dir = dir.buf;
    p.shift = shift.buf;
    p.base = base.buf;
    p.b = b.buf;
    Py_ssize_t n_sets = masks.len / nc;
    p.cols = malloc(sizeof(int) * (N + 1));
    p.state = malloc(sizeof(int) * (N + 1));
    p.bv = malloc(sizeof(int) * m);
    p.Binv = malloc(d * m * m);
    p.xB = malloc(d * m);
    p.cB = malloc(d * m);
    p.y = malloc(d * m);
    p.alpha = malloc(d * m);
    p.r = malloc(d * m);
    p.z = malloc(d * (N + 1));
    PyObject *status = PyBytes_FromStringAndSize(NULL, n_sets);
    PyObject *forces = PyBytes_FromStringAndSize(NULL, (Py_ssize_t)(n_sets * 2 * nc * d));
    if (!(p.cols && p.state && p.bv && p.Binv && p.xB && p.cB && p.y && p.alpha && p.r && p.z && status && forces)) {
        Py_XDECREF(status);
        Py_XDECREF(forces);
        PyErr_NoMemory();
        goto done;
    }
    signed char *st = (signed char *)PyBytes_AS_STRING(status);
    double *fo = (double *)PyBytes_AS_STRING(forces);
    memset(fo, 0, (size_t)n_sets * 2 * nc * d);
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t s = 0; s < n_sets; s++)
        st[s] = (signed char)relax_one(&p, (const unsigned char *)masks.buf + s * nc, fo + (size_t)s * 2 * nc);
    Py_END_ALLOW_THREADS
    result = Py_BuildValue("(NN)", status, forces);
done:
    free(p.cols); free(p.state); free(p.bv); free(p.Binv); free(p.xB); free(p.cB); free(p.y); free(p.alpha);
    free(p.r); free(p.z);
    PyBuffer_Release(&G); PyBuffer_Release(&ub); PyBuffer_Release(&gnorm); PyBuffer_Release(&owner);
    PyBuffer_Release(&dir); PyBuffer_Release(&shift); PyBuffer_Release(&base); PyBuffer_Release(&b);
    PyBuffer_Release(&masks);
    return result;
}

static PyMethodDef methods[] = {
    {"screen", screen, METH_VARARGS,
     "screen(M, drive, E, rhs, mu, masks, n_c, dof, vmargin, slip, force_rel, red_sing, coulomb)\n"
     "-> (codes: bytes, pruned_kinematic, pruned_coulomb, modes)\n\n"
     "The reduced screen of qsplan.mechanics.solver.screen.screen_set for every breaking set (a row of masks,\n"
     "uint8, 1 = breaking), compiled; codes holds the kept modes' letter codes, n_c bytes each, in order."},
    {"relax", relax, METH_VARARGS,
     "relax(G, ub, gnorm, owner, dir, shift, base, b, masks, n_c, m, N, maxit, dtol, ptol, feas_tol, cert_margin,\n"
     "      proof_ratio) -> (status: bytes of int8, forces: bytes of float64 (s, 2 n_c))\n\n"
     "The equilibrium relaxation of qsplan.mechanics.solver.breaking_sets for every breaking set (a row of masks):\n"
     "1 feasible (its force returned), 0 proven infeasible (a checked Farkas certificate), -1 undecided."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "screen_kernel",
                                    "The compiled reduced screen of the pruned mode search (see screen_kernel.c).", -1,
                                    methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit_screen_kernel(void)
{
    PyObject *m = PyModule_Create(&module);
    if (m && PyModule_AddIntConstant(m, "ABI", 2) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
