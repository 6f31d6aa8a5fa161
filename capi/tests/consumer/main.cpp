// A C++ program of an outside project: solves one problem through the installed eopnp.hpp.
#include <eopnp.hpp>

#include <cmath>
#include <cstdio>

int main() {
  const double world[6 * 3] = {-1, -1, 0.5, 1, -1, -0.5, 1, 1, 0.2, -1, 1, -0.1, 0.3, 0.2, 1, -0.4, 0.6, -0.8};
  double pixels[6 * 2];
  const auto camera = eopnp::Camera::pinhole(800.0, 800.0, 320.0, 240.0);
  for (int i = 0; i < 6; ++i) {
    const double z = world[3 * i + 2] + 6.0;
    const auto px = camera.project((world[3 * i] + 0.1) / z, (world[3 * i + 1] - 0.2) / z);
    pixels[2 * i] = px[0];
    pixels[2 * i + 1] = px[1];
  }
  try {
    const eopnp::Solution s = eopnp::Solver().solve(eopnp::Problem::pixels(world, pixels, 6, camera));
    std::printf("eopnp %s (C++): t = (%.6f, %.6f, %.6f)\n", eopnp_version(), s.translation[0],
                s.translation[1], s.translation[2]);
    eopnp::Solver().solve(eopnp::Problem::pixels(world, pixels, 3, camera));
  } catch (const eopnp::TooFewPointsError& e) {
    std::printf("three points: eopnp::TooFewPointsError: %s\n", e.what());
    return 0;
  }
  return 1;
}
