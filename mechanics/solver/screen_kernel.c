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
    c->eq_ok = 1;
}

/* The equilibrium and Coulomb screen of the mode at vertex u: 1 to prune, 0 to keep. */
static int coulomb_prunes(Ctx *c, const double *u)
{
    int nA = c->nA, r = c->r, nS = c->nS;
    double *K = c->K, *h = c->h;
    int k = 0;
    for (int s = 0; s < nA; s++) {
        if (c->rolling[s])
            continue;
        double vt = -c->tx[s];
        for (int q = 0; q < r; q++)
            vt += c->TZ[s * r + q] * u[q];
        if (!(fabs(vt) > c->slip))
            return 0; /* xi (eq. 16) not certain: the reference decides */
        double mx = c->mu[c->A[s]] * (vt > 0 ? 1.0 : -1.0);
        const double *Nn = c->NB + (size_t)s * nS, *Nt = c->NB + (size_t)(nA + s) * nS;
        for (int q = 0; q < nS; q++)
            K[k * nS + q] = Nt[q] + mx * Nn[q];
        h[k] = -(c->y0[nA + s] + mx * c->y0[s]);
        k++;
    }
    /* one LU with partial pivoting: the determinant for the guard, then the solve */
    double ratio = 1.0;
    for (int i = 0; i < nS; i++) {
        double nn = 0.0;
        for (int q = 0; q < nS; q++)
            nn += K[i * nS + q] * K[i * nS + q];
        if (nn == 0.0)
            return 0;
        ratio /= sqrt(nn);
    }
    for (int j = 0; j < nS; j++) {
        int p = j;
        double best = fabs(K[j * nS + j]);
        for (int i = j + 1; i < nS; i++)
            if (fabs(K[i * nS + j]) > best) {
                best = fabs(K[i * nS + j]);
                p = i;
            }
        if (best == 0.0)
            return 0;
        if (p != j) {
            for (int q = 0; q < nS; q++) {
                double t = K[j * nS + q];
                K[j * nS + q] = K[p * nS + q];
                K[p * nS + q] = t;
            }
            double t = h[j];
            h[j] = h[p];
            h[p] = t;
        }
        double inv = 1.0 / K[j * nS + j];
        ratio *= best;
        for (int i = j + 1; i < nS; i++) {
            double f = K[i * nS + j] * inv;
            for (int q = j + 1; q < nS; q++)
                K[i * nS + q] -= f * K[j * nS + q];
            h[i] -= f * h[j];
        }
    }
    if (!(ratio >= c->red_sing))
        return 0;
    double *w = c->u + r; /* after u */
    for (int i = nS - 1; i >= 0; i--) {
        double s = h[i];
        for (int q = i + 1; q < nS; q++)
            s -= K[i * nS + q] * w[q];
        w[i] = s / K[i * nS + i];
    }
    /* ||c||_2^2 = ||c0||^2 + ||w||^2 (c0, the least-norm force, is orthogonal to N's columns) bounds F:
     * a slack below -force_rel * Fup prunes at once (2: room for rounding; the exact test would too) */
    double ww = c->c0norm2;
    for (int q = 0; q < nS; q++)
        ww += w[q] * w[q];
    double Fup = 2.0 * fmax(c->rhs_max, sqrt(ww)), early = -c->force_rel * Fup;
    double F = c->rhs_max, worst = INFINITY;
    for (int s = 0; s < nA; s++) {
        double cn = c->y0[s], ct = c->y0[nA + s];
        const double *Nn = c->NB + (size_t)s * nS, *Nt = c->NB + (size_t)(nA + s) * nS;
        for (int q = 0; q < nS; q++) {
            cn += Nn[q] * w[q];
            ct += Nt[q] * w[q];
        }
        if (fabs(cn) > F)
            F = fabs(cn);
        if (cn < worst)
            worst = cn;
        if (c->rolling[s]) { /* eq. (28) */
            double m = c->mu[c->A[s]] * cn;
            if (fabs(ct) > F)
                F = fabs(ct);
            if (m + ct < worst)
                worst = m + ct;
            if (m - ct < worst)
                worst = m - ct;
        }
        if (worst < early)
            return 1;
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
    if (f == 2) { /* the leaves in pairs (i, l): a 2 x 2 system fixes the last two coordinates (Cramer) */
        const double *cB = coef + (size_t)nA * r, *dB = cst + nA;
        const int *cm = c->colmap + (size_t)j * r;
        double vm = c->vmargin;
        for (int i = last + 1; i < nA - 1; i++) {
            double a0 = coef[(size_t)i * r], a1 = coef[(size_t)i * r + 1], ci = cst[i];
            double ri = ratio * c->inv_tznorm[i];
            c->rolling[i] = 1;
            c->n_total += nA - 1 - i;
            for (int l = i + 1; l < nA; l++) {
                double b0 = coef[(size_t)l * r], b1 = coef[(size_t)l * r + 1], cl = cst[l];
                double det = a0 * b1 - a1 * b0, rat = ri * fabs(det) * c->inv_tznorm[l];
                int rc = 0;
                if (!(rat >= c->red_sing)) { /* not trusted (or singular): the reference decides */
                    c->rolling[l] = 1;
                    rc = emit(c);
                    c->rolling[l] = 0;
                } else {
                    double id = 1.0 / det, t0 = (a1 * cl - b1 * ci) * id, t1 = (b0 * ci - a0 * cl) * id;
                    int k = 0;
                    while (k < b && !(dB[k] + cB[(size_t)k * r] * t0 + cB[(size_t)k * r + 1] * t1 < -vm))
                        k++;
                    if (k < b) {
                        c->n_kin++;
                    } else {
                        c->rolling[l] = 1;
                        c->u[cm[0]] = t0;
                        c->u[cm[1]] = t1;
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
    if (!(c.A && c.Bc && c.rolling && c.code && c.Z && c.x0 && c.TZ && c.tx && c.tznorm && c.NB && c.y0 &&
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
    free(c.tx); free(c.tznorm); free(c.NB); free(c.y0); free(c.coef); free(c.cst); free(c.inv_tznorm); free(c.path_i); free(c.path_p); free(c.colmap); free(c.qr); free(c.q); free(c.beta);
    free(c.u); free(c.K); free(c.h); free(c.y); free(c.out);
    PyBuffer_Release(&M); PyBuffer_Release(&drive); PyBuffer_Release(&E);
    PyBuffer_Release(&rhs); PyBuffer_Release(&mu); PyBuffer_Release(&masks);
    return result;
}

static PyMethodDef methods[] = {
    {"screen", screen, METH_VARARGS,
     "screen(M, drive, E, rhs, mu, masks, n_c, dof, vmargin, slip, force_rel, red_sing, coulomb)\n"
     "-> (codes: bytes, pruned_kinematic, pruned_coulomb, modes)\n\n"
     "The reduced screen of qsplan.mechanics.solver.screen.screen_set for every breaking set (a row of masks,\n"
     "uint8, 1 = breaking), compiled; codes holds the kept modes' letter codes, n_c bytes each, in order."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "screen_kernel",
                                    "The compiled reduced screen of the pruned mode search (see screen_kernel.c).", -1,
                                    methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit_screen_kernel(void)
{
    PyObject *m = PyModule_Create(&module);
    if (m && PyModule_AddIntConstant(m, "ABI", 1) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
