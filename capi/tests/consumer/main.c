/* A C program of an outside project: solves one problem through the installed eopnp. */
#include <eopnp.h>
#include <math.h>
#include <stdio.h>

int main(void) {
  double world[6 * 3] = {-1, -1, 0.5, 1, -1, -0.5, 1, 1, 0.2, -1, 1, -0.1, 0.3, 0.2, 1, -0.4, 0.6, -0.8};
  double image[6 * 2];
  for (int i = 0; i < 6; ++i) { /* R = I, t = (0.1, -0.2, 6) */
    double z = world[3 * i + 2] + 6.0;
    image[2 * i] = (world[3 * i] + 0.1) / z;
    image[2 * i + 1] = (world[3 * i + 1] - 0.2) / z;
  }
  EopnpSolver *solver = NULL;
  EopnpSolution s;
  EopnpProblem p = {0};
  p.n = 6;
  p.world = world;
  p.image = image;
  if (eopnp_solver_create(&solver) != EOPNP_OK || eopnp_solve(solver, &p, &s) != EOPNP_OK) {
    fprintf(stderr, "eopnp: %s\n", eopnp_last_error_message());
    return 1;
  }
  eopnp_solver_free(solver);
  printf("eopnp %s (C): t = (%.6f, %.6f, %.6f)\n", eopnp_version(), s.translation[0], s.translation[1],
         s.translation[2]);
  return fabs(s.translation[2] - 6.0) < 1e-9 ? 0 : 1;
}
