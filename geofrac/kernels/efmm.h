void efmm_stress_mass(double *A, const double *w, const double *c, const double *coordinate_dofs,
                      const int *entity_local_index, const uint8_t *quadrature_permutation,
                      void *custom_data);
void efmm_coupling(double *A, const double *w, const double *c, const double *coordinate_dofs,
                   const int *entity_local_index, const uint8_t *quadrature_permutation,
                   void *custom_data);
