/* C-MultiMLSM node field and node stiffness (Edo (2016), App. C, eqs. 3.12-3.28); the numpy
 * reference with the full derivation is geofrac/mls/cmulti.py. A plain function, not a
 * ufcx kernel.
 *
 * Node i has n satellites at offsets d_j = x_j - x_i (0 < |d_j| < h). In the scaled offsets
 * xi = d/h the field is u(x) = u_i + F(xi) G u_nodes, u_nodes = (u_i, v_i, u_1, v_1, ...),
 * with G = A^-1 C (eqs. 3.21-3.24), A = sum_j W_j F_j^T F_j, C = [-sum_j W_j F_j^T,
 * W_1 F_1^T, ..., W_n F_n^T], W the quartic spline (3.13). F has m = 10, 4, 1, 0 columns
 * for orders 2, 1, 0, -1 (C.8, 3.18a, rotation only, fragment).
 *
 * Order rule (same as the numpy reference): starting at `order`, Cholesky-factorise A and
 * accept when every pivot is positive and min(diag L)^2 >= 1e-12 max(diag L)^2; otherwise
 * try the next lower order. Order -1 always succeeds.
 *
 * The stiffness (3.27-3.28) K = t sum_T int_T B^T D B, B = S(x) G with S the Voigt strain
 * rows of dF/dx (3 x m), is computed as K = G^T M G, M = t sum_g w_g S^T D S (m x m), with
 * the three-point Gauss rule of degree 2 on each sub-triangle (exact: B is linear).
 *
 * Arguments:
 *   n: number of satellites (>= 0); order: starting order (2, 1, 0 or -1); h > 0.
 *   xy: satellite offsets from the node, n x 2 (physical units).
 *   nsub, tri: sub-triangles of the node's grain, nsub x 3 x 2, offsets from the node.
 *   D: elasticity matrix 3 x 3 row-major (Voigt, engineering shear); t: thickness.
 *   G (out): room for m(order) x 2(n+1) values (the starting order's m), row-major; the
 *     first m(accepted) rows are filled with the scaled coefficients A^-1 C.
 *   K (out): 2(n+1) x 2(n+1), row-major.
 * Returns the accepted order, or -2 for invalid arguments (nothing written then).
 */
#include <math.h>
#include <string.h>

#define MAXM 10
#define MIN_PIVOT_RATIO 1e-12
#define PI 3.14159265358979323846

static const int TERMS[4] = {0, 1, 4, 10}; /* m of orders -1, 0, 1, 2 */

/* Three-point Gauss rule of degree 2 on a triangle (barycentric points, weight 1/3). */
static const double GAUSS[3][3] = {{2.0 / 3, 1.0 / 6, 1.0 / 6},
                                   {1.0 / 6, 2.0 / 3, 1.0 / 6},
                                   {1.0 / 6, 1.0 / 6, 2.0 / 3}};

/* Quartic spline weight (3.13) of a satellite at scaled offset (x, y). */
static double weight(double x, double y, double h)
{
  const double s = sqrt(x * x + y * y);
  if (s > 1.0)
    return 0.0;
  return 5.0 / (PI * h * h) * (1.0 - 6.0 * s * s + 8.0 * s * s * s - 3.0 * s * s * s * s);
}

/* F at (x, y): F[0] row u, F[1] row v, first m(order) entries of each. */
static void basis(int order, double x, double y, double F[2][MAXM])
{
  memset(F, 0, 2 * MAXM * sizeof(double));
  if (order >= 0)
  {
    F[0][0] = -y;
    F[1][0] = x;
  }
  if (order >= 1)
  {
    F[0][1] = x;
    F[1][2] = y;
    F[0][3] = 0.5 * y;
    F[1][3] = 0.5 * x;
  }
  if (order >= 2)
  {
    F[0][4] = 0.5 * x * x;
    F[0][5] = x * y;
    F[1][5] = -0.5 * x * x;
    F[0][6] = -0.5 * y * y;
    F[1][6] = x * y;
    F[1][7] = 0.5 * y * y;
    F[1][8] = 0.5 * x * x;
    F[0][9] = 0.5 * y * y;
  }
}

/* Voigt strain rows of dF/dxi at (x, y): S[0] = du/dx, S[1] = dv/dy, S[2] = du/dy + dv/dx
 * (derivatives with respect to the scaled offsets; divide by h for physical ones). */
static void strain_rows(int order, double x, double y, double S[3][MAXM])
{
  memset(S, 0, 3 * MAXM * sizeof(double));
  /* rotation: du/dy = -1 and dv/dx = 1 cancel in the shear, so column 0 stays zero */
  if (order >= 1)
  {
    S[0][1] = 1.0;
    S[1][2] = 1.0;
    S[2][3] = 1.0;
  }
  if (order >= 2)
  {
    S[0][4] = x;
    S[0][5] = y;
    /* S[2][5] = 0: du/dy = x and dv/dx = -x cancel */
    S[1][6] = x;
    /* S[2][6] = 0: du/dy = -y and dv/dx = y cancel */
    S[1][7] = y;
    S[2][8] = x;
    S[2][9] = y;
  }
}

/* In-place Cholesky A = L L^T (lower triangle of a), with the pivot rule; 1 if accepted. */
static int cholesky(int m, double a[MAXM][MAXM])
{
  double dmin = INFINITY, dmax = 0.0;
  for (int j = 0; j < m; ++j)
  {
    double s = a[j][j];
    for (int k = 0; k < j; ++k)
      s -= a[j][k] * a[j][k];
    if (!(s > 0.0) || !isfinite(s))
      return 0;
    const double ljj = sqrt(s);
    a[j][j] = ljj;
    dmin = fmin(dmin, ljj);
    dmax = fmax(dmax, ljj);
    for (int i = j + 1; i < m; ++i)
    {
      double r = a[i][j];
      for (int k = 0; k < j; ++k)
        r -= a[i][k] * a[j][k];
      a[i][j] = r / ljj;
    }
  }
  return dmin * dmin >= MIN_PIVOT_RATIO * dmax * dmax;
}

int cmulti_node(int n, int order, double h, const double *xy, int nsub, const double *tri,
                const double *D, double t, double *G, double *K)
{
  if (n < 0 || nsub < 0 || order < -1 || order > 2 || !(h > 0.0))
    return -2;
  const int ncol = 2 * (n + 1);
  memset(K, 0, (size_t)ncol * ncol * sizeof(double));
  int m = 0;
  double L[MAXM][MAXM];
  for (; order >= 0; --order)
  {
    m = TERMS[order + 1];
    memset(L, 0, sizeof(L));
    for (int j = 0; j < n; ++j)
    {
      const double x = xy[2 * j] / h, y = xy[2 * j + 1] / h;
      const double w = weight(x, y, h);
      double F[2][MAXM];
      basis(order, x, y, F);
      for (int p = 0; p < m; ++p)
        for (int q = 0; q <= p; ++q)
          L[p][q] += w * (F[0][p] * F[0][q] + F[1][p] * F[1][q]);
    }
    if (cholesky(m, L))
      break;
  }
  if (order < 0)
    return -1; /* fragment: no coefficients, K = 0 */

  /* C (eq. 3.22) into G, column by column, then G = L^-T L^-1 C. */
  memset(G, 0, (size_t)m * ncol * sizeof(double));
  for (int j = 0; j < n; ++j)
  {
    const double x = xy[2 * j] / h, y = xy[2 * j + 1] / h;
    const double w = weight(x, y, h);
    double F[2][MAXM];
    basis(order, x, y, F);
    for (int p = 0; p < m; ++p)
      for (int c = 0; c < 2; ++c)
      {
        G[p * ncol + 2 * (j + 1) + c] = w * F[c][p];
        G[p * ncol + c] -= w * F[c][p];
      }
  }
  for (int col = 0; col < ncol; ++col)
  {
    double z[MAXM];
    for (int p = 0; p < m; ++p) /* L z = c */
    {
      double r = G[p * ncol + col];
      for (int k = 0; k < p; ++k)
        r -= L[p][k] * z[k];
      z[p] = r / L[p][p];
    }
    for (int p = m - 1; p >= 0; --p) /* L^T g = z */
    {
      double r = z[p];
      for (int k = p + 1; k < m; ++k)
        r -= L[k][p] * z[k];
      z[p] = r / L[p][p];
    }
    for (int p = 0; p < m; ++p)
      G[p * ncol + col] = z[p];
  }
  if (order == 0)
    return 0; /* rigid rotation: B = 0, K = 0 */

  /* M = t sum_g w_g S^T D S / h^2 over the Gauss points of the sub-triangles. */
  double M[MAXM][MAXM];
  memset(M, 0, sizeof(M));
  for (int s = 0; s < nsub; ++s)
  {
    const double *a = tri + 6 * s, *b = a + 2, *c = a + 4;
    const double area = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    for (int g = 0; g < 3; ++g)
    {
      const double gx = GAUSS[g][0] * a[0] + GAUSS[g][1] * b[0] + GAUSS[g][2] * c[0];
      const double gy = GAUSS[g][0] * a[1] + GAUSS[g][1] * b[1] + GAUSS[g][2] * c[1];
      double S[3][MAXM], DS[3][MAXM];
      strain_rows(order, gx / h, gy / h, S);
      for (int r = 0; r < 3; ++r)
        for (int q = 0; q < m; ++q)
          DS[r][q] = D[3 * r] * S[0][q] + D[3 * r + 1] * S[1][q] + D[3 * r + 2] * S[2][q];
      const double wg = t * area / (3.0 * h * h);
      for (int p = 0; p < m; ++p)
        for (int q = 0; q < m; ++q)
          M[p][q] += wg * (S[0][p] * DS[0][q] + S[1][p] * DS[1][q] + S[2][p] * DS[2][q]);
    }
  }
  /* K = G^T M G: row a of K is (G^T M)_a G. */
  for (int a = 0; a < ncol; ++a)
  {
    double r[MAXM];
    for (int q = 0; q < m; ++q)
    {
      double s = 0.0;
      for (int p = 0; p < m; ++p)
        s += G[p * ncol + a] * M[p][q];
      r[q] = s;
    }
    for (int b = 0; b < ncol; ++b)
    {
      double s = 0.0;
      for (int q = 0; q < m; ++q)
        s += r[q] * G[q * ncol + b];
      K[a * ncol + b] = s;
    }
  }
  return order;
}
