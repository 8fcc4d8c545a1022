double cell_stresses(int64_t nc, int nd, const int64_t *dofs, const double *u, const double *S,
                     const double *K, const unsigned char *use, double *s1, double *stress);
