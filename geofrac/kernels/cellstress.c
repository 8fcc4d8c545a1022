/* Element cells' midpoint stresses, largest principal stress and strain energy.
 *
 * For every cell c with use[c] != 0: u_c = u[dofs[c, :]] (nd values),
 *   sigma_c = S[c] u_c, S[c] shape (9, nd): rows 3q + i, midpoint q, component i
 *             (xx, yy, xy);
 *   s1[c, q] = the largest in-plane principal stress of midpoint q;
 *   stress[c, :] = sigma_c when stress is not NULL;
 *   energy += 0.5 u_c . (K[c] u_c), K[c] shape (nd, nd).
 * Cells with use[c] == 0 are skipped (their s1 and stress rows are left as they are).
 * Returns the energy. The numpy reference is geofrac.fracture.units.cell_stresses_numpy.
 */
#include <math.h>
#include <stdint.h>

double cell_stresses(int64_t nc, int nd, const int64_t *dofs, const double *u, const double *S,
                     const double *K, const unsigned char *use, double *s1, double *stress)
{
    double energy = 0.0;
    double uc[64];
    if (nd > 64)
        return NAN;
    for (int64_t c = 0; c < nc; ++c) {
        if (!use[c])
            continue;
        const int64_t *d = dofs + c * nd;
        for (int p = 0; p < nd; ++p)
            uc[p] = u[d[p]];
        const double *Sc = S + c * 9 * nd;
        double sig[9];
        for (int r = 0; r < 9; ++r) {
            double acc = 0.0;
            for (int p = 0; p < nd; ++p)
                acc += Sc[r * nd + p] * uc[p];
            sig[r] = acc;
        }
        for (int q = 0; q < 3; ++q) {
            double sx = sig[3 * q], sy = sig[3 * q + 1], txy = sig[3 * q + 2];
            s1[3 * c + q] = 0.5 * (sx + sy) + hypot(0.5 * (sx - sy), txy);
        }
        if (stress)
            for (int r = 0; r < 9; ++r)
                stress[9 * c + r] = sig[r];
        const double *Kc = K + c * nd * nd;
        double e = 0.0;
        for (int i = 0; i < nd; ++i) {
            double acc = 0.0;
            for (int j = 0; j < nd; ++j)
                acc += Kc[i * nd + j] * uc[j];
            e += uc[i] * acc;
        }
        energy += 0.5 * e;
    }
    return energy;
}
