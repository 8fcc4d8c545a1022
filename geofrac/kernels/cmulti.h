int cmulti_node(int n, int order, double h, const double *xy, int nsub, const double *tri,
                const double *D, double t, double *G, double *K);
