double cell_stresses(long nc, int nd, const long *dofs, const double *u, const double *S,
                     const double *K, const unsigned char *use, double *s1, double *stress);
