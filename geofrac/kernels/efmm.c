/* EFMM cell kernels (Edo (2016), §3.2, eqs. 3.2b, 3.4a, 3.4b, 3.7; Fig. 3.3), ufcx signature.
 *
 * Node j of a triangle owns the part (x_j, X_a, p, X_b) of the cell, integrated as the two
 * sub-triangles (x_j, X_a, p) and (x_j, p, X_b): p is the cell's inner point, X_a the
 * crossing on edge (j, j+1) and X_b the crossing on edge (j-1, j). The stress basis of
 * node j is P_j = I3 (x) [1, (x - x_j)/h, (y - y_j)/h] (eq. 3.2b, a complete linear field
 * per node), h a length fixed for the whole mesh, so every cell around a node uses the
 * same basis and the cell pieces sum to the node's A_i and C_i.
 *
 * w (coefficient, per cell, 8 values): p, then X_0, X_1, X_2 (X_k on the edge opposite
 *   local vertex k), all (x, y).
 * c (constants, 10 values): D^-1 row-major in Voigt order (xx, yy, xy with engineering
 *   shear), then h.
 * coordinate_dofs: the three vertices, (x, y, z) each.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

/* Three-point Gauss rule of degree 2 on a triangle (barycentric points, weight 1/3). */
static const double G[3][3] = {{2.0 / 3, 1.0 / 6, 1.0 / 6},
                               {1.0 / 6, 2.0 / 3, 1.0 / 6},
                               {1.0 / 6, 1.0 / 6, 2.0 / 3}};

/* Moments of node j's part of the cell: m1 = (int 1, int s, int t), m2 = int q q^T,
 * q = (1, s, t), s = (x - x_j)/h, t = (y - y_j)/h. */
static void node_moments(const double *w, const double *x, int j, double h,
                         double m1[3], double m2[3][3])
{
  const double *p = w;
  const double *xa = w + 2 + 2 * ((j + 2) % 3); /* edge (j, j+1) is opposite j+2 */
  const double *xb = w + 2 + 2 * ((j + 1) % 3); /* edge (j-1, j) is opposite j+1 */
  const double xj[2] = {x[3 * j], x[3 * j + 1]};
  const double *tri[2][3] = {{xj, xa, p}, {xj, p, xb}};
  memset(m1, 0, 3 * sizeof(double));
  memset(m2, 0, 9 * sizeof(double));
  for (int s = 0; s < 2; ++s)
  {
    const double *a = tri[s][0], *b = tri[s][1], *c = tri[s][2];
    const double area = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
    for (int g = 0; g < 3; ++g)
    {
      const double gx = G[g][0] * a[0] + G[g][1] * b[0] + G[g][2] * c[0];
      const double gy = G[g][0] * a[1] + G[g][1] * b[1] + G[g][2] * c[1];
      const double q[3] = {1.0, (gx - xj[0]) / h, (gy - xj[1]) / h};
      const double wg = area / 3.0;
      for (int m = 0; m < 3; ++m)
      {
        m1[m] += wg * q[m];
        for (int n = 0; n < 3; ++n)
          m2[m][n] += wg * q[m] * q[n];
      }
    }
  }
}

/* Linear form on a vertex field of block size 81: node j's piece of A_j (eq. 3.4a),
 * A[j*81 + (a*3+m)*9 + (b*3+n)] = Dinv[a][b] * int q_m q_n. */
void efmm_stress_mass(double *restrict A, const double *restrict w, const double *restrict c,
                      const double *restrict coordinate_dofs,
                      const int *restrict entity_local_index,
                      const uint8_t *restrict quadrature_permutation, void *custom_data)
{
  (void)entity_local_index;
  (void)quadrature_permutation;
  (void)custom_data;
  const double h = c[9];
  for (int j = 0; j < 3; ++j)
  {
    double m1[3], m2[3][3];
    node_moments(w, coordinate_dofs, j, h, m1, m2);
    for (int a = 0; a < 3; ++a)
      for (int m = 0; m < 3; ++m)
        for (int b = 0; b < 3; ++b)
          for (int n = 0; n < 3; ++n)
            A[j * 81 + (a * 3 + m) * 9 + b * 3 + n] += c[a * 3 + b] * m2[m][n];
  }
}

/* Bilinear form, test = stress coefficients (vertex field of block size 9), trial = CST
 * displacement (block size 2): node j's piece of C_j (eq. 3.4b),
 * A[(j*9 + a*3+m) * 6 + k*2 + d] = int q_m * B[a][k*2+d]. */
void efmm_coupling(double *restrict A, const double *restrict w, const double *restrict c,
                   const double *restrict coordinate_dofs,
                   const int *restrict entity_local_index,
                   const uint8_t *restrict quadrature_permutation, void *custom_data)
{
  (void)entity_local_index;
  (void)quadrature_permutation;
  (void)custom_data;
  const double *x = coordinate_dofs;
  const double h = c[9];
  const double det = (x[3] - x[0]) * (x[7] - x[1]) - (x[6] - x[0]) * (x[4] - x[1]);
  /* CST gradients of the barycentric coordinates: dN_k/dx = bk/det, dN_k/dy = ck/det */
  const double bx[3] = {(x[4] - x[7]) / det, (x[7] - x[1]) / det, (x[1] - x[4]) / det};
  const double by[3] = {(x[6] - x[3]) / det, (x[0] - x[6]) / det, (x[3] - x[0]) / det};
  double B[3][6];
  memset(B, 0, sizeof(B));
  for (int k = 0; k < 3; ++k)
  {
    B[0][2 * k] = bx[k];     /* eps_x = du/dx */
    B[1][2 * k + 1] = by[k]; /* eps_y = dv/dy */
    B[2][2 * k] = by[k];     /* gamma_xy = du/dy + dv/dx */
    B[2][2 * k + 1] = bx[k];
  }
  for (int j = 0; j < 3; ++j)
  {
    double m1[3], m2[3][3];
    node_moments(w, x, j, h, m1, m2);
    for (int a = 0; a < 3; ++a)
      for (int m = 0; m < 3; ++m)
        for (int col = 0; col < 6; ++col)
          A[(j * 9 + a * 3 + m) * 6 + col] += m1[m] * B[a][col];
  }
}
