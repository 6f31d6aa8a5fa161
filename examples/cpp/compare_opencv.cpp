// eopnp from C++ against OpenCV's cv::solvePnP (SOLVEPNP_ITERATIVE and SOLVEPNP_SQPNP) on the
// same synthetic problems: pixels of a 800 px pinhole camera (640 x 480, no distortion) with
// Gaussian noise of sigma = 1 px, N = 10, 100, 1000 points in front of the camera at a random
// pose, a fixed seed. For each method and N: the median time of one solve (one thread; each
// problem solved `--repetitions` times, the median over problems of the mean per solve), the
// median pixel cost (sum of squared reprojection errors, px^2) and, against ITERATIVE, how many
// problems get a cost higher by more than 1e-9 relative (rounding: both methods converge to the
// same minimum) and the largest relative difference (cost - ITERATIVE's) / ITERATIVE's.
// Prints the poses of the first problem of each N.
//
// Built by the CMake project with -DEOPNP_BUILD_EXAMPLES=ON (needs OpenCV):
//   build/examples/cpp/compare_opencv [--repetitions R] [--problems P]
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "eopnp.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace {

// A 64-bit LCG (portable, unlike the standard distributions).
struct Lcg {
  std::uint64_t s;
  double uniform() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(s >> 11) / 9007199254740992.0;
  }
  double range(double a, double b) { return a + (b - a) * uniform(); }
  double normal() {  // Box-Muller
    const double u = 1.0 - uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  }
};

constexpr double F = 800.0, CX = 320.0, CY = 240.0;

struct Case {
  std::vector<double> world, pixels;  // 3 N, 2 N
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
};

Case make_case(Lcg& g, int n) {
  cv::Mat r;
  const cv::Mat rvec = (cv::Mat_<double>(3, 1) << g.range(-3, 3), g.range(-3, 3), g.range(-3, 3));
  cv::Rodrigues(rvec, r);
  const cv::Vec3d t(g.range(-1, 1), g.range(-1, 1), g.range(4, 8));
  Case c;
  for (int i = 0; i < n; ++i) {
    const cv::Vec3d pc(g.range(-2, 2), g.range(-1.5, 1.5), g.range(4, 8));
    const cv::Mat x = r.t() * cv::Mat(pc - t);
    const double u = F * pc[0] / pc[2] + CX + g.normal(), v = F * pc[1] / pc[2] + CY + g.normal();
    c.world.insert(c.world.end(), {x.at<double>(0), x.at<double>(1), x.at<double>(2)});
    c.pixels.insert(c.pixels.end(), {u, v});
    c.obj.emplace_back(x.at<double>(0), x.at<double>(1), x.at<double>(2));
    c.img.emplace_back(u, v);
  }
  return c;
}

// Sum of squared pixel reprojection errors of the pose (R row-major, t).
double pixel_cost(const Case& c, const double* r, const double* t) {
  double cost = 0.0;
  const std::size_t n = c.obj.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double* x = &c.world[3 * i];
    const double xc = r[0] * x[0] + r[1] * x[1] + r[2] * x[2] + t[0];
    const double yc = r[3] * x[0] + r[4] * x[1] + r[5] * x[2] + t[1];
    const double zc = r[6] * x[0] + r[7] * x[1] + r[8] * x[2] + t[2];
    const double du = F * xc / zc + CX - c.pixels[2 * i], dv = F * yc / zc + CY - c.pixels[2 * i + 1];
    cost += du * du + dv * dv;
  }
  return cost;
}

struct Pose {
  double r[9], t[3];
};

Pose from_cv(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Pose p;
  for (int i = 0; i < 9; ++i) p.r[i] = r.at<double>(i / 3, i % 3);
  for (int i = 0; i < 3; ++i) p.t[i] = tvec.at<double>(i);
  return p;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Mean time of one call over `reps` calls, microseconds.
double time_us(int reps, const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < reps; ++i) f();
  const auto t1 = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::micro>(t1 - t0).count() / reps;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 200, problems = 30;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--repetitions") == 0) reps = std::max(1, std::atoi(argv[i + 1]));
    if (std::strcmp(argv[i], "--problems") == 0) problems = std::max(1, std::atoi(argv[i + 1]));
  }
  cv::setNumThreads(1);
  const cv::Mat k = (cv::Mat_<double>(3, 3) << F, 0, CX, 0, F, CY, 0, 0, 1);
  const cv::Mat dist;
  const double kr[9] = {F, 0, CX, 0, F, CY, 0, 0, 1};
  const eopnp::Camera cam = eopnp::Camera::opencv(kr, nullptr, 0);
  const eopnp::Solver solver;
  std::printf("OpenCV %s, eopnp %s; pixels of a %.0f px pinhole camera, sigma = 1 px; %d problems per N, %d "
              "repetitions (one thread); times are medians over the problems\n\n",
              CV_VERSION, eopnp_version(), F, problems, reps);
  std::printf("| N | method | median time (us) | median pixel cost (px^2) | cost above ITERATIVE's by > 1e-9 | "
              "largest relative cost difference to ITERATIVE |\n");
  std::printf("|---|---|---|---|---|---|\n");
  Lcg g{20261129};
  std::vector<std::string> poses;
  for (int n : {10, 100, 1000}) {
    const int r = n >= 1000 ? std::max(1, reps / 10) : reps;
    std::vector<Case> cases;
    for (int p = 0; p < problems; ++p) cases.push_back(make_case(g, n));
    const char* names[4] = {"cv::solvePnP ITERATIVE", "cv::solvePnP SQPNP", "eopnp (eopnp.hpp)",
                            "eopnp::cv::solvePnP"};
    std::vector<double> times[4], costs[4];
    int above[4] = {0, 0, 0, 0};
    double worst[4] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t p = 0; p < cases.size(); ++p) {
      const Case& c = cases[p];
      Pose pose[4];
      cv::Mat rv, tv;
      auto iterative = [&] { cv::solvePnP(c.obj, c.img, k, dist, rv, tv, false, cv::SOLVEPNP_ITERATIVE); };
      auto sqpnp = [&] { cv::solvePnP(c.obj, c.img, k, dist, rv, tv, false, cv::SOLVEPNP_SQPNP); };
      eopnp::Solution s{};
      const eopnp::Problem problem =
          eopnp::Problem::pixels(c.world.data(), c.pixels.data(), static_cast<std::size_t>(n), cam);
      auto ours = [&] { s = solver.solve(problem); };
      auto ours_cv = [&] { eopnp::cv::solvePnP(c.obj, c.img, k, dist, rv, tv); };
      times[0].push_back(time_us(r, iterative));
      pose[0] = from_cv(rv, tv);
      times[1].push_back(time_us(r, sqpnp));
      pose[1] = from_cv(rv, tv);
      times[2].push_back(time_us(r, ours));
      std::memcpy(pose[2].r, s.rotation, sizeof pose[2].r);
      std::memcpy(pose[2].t, s.translation, sizeof pose[2].t);
      times[3].push_back(time_us(r, ours_cv));
      pose[3] = from_cv(rv, tv);
      const double base = pixel_cost(c, pose[0].r, pose[0].t);
      for (int m = 0; m < 4; ++m) {
        const double cost = pixel_cost(c, pose[m].r, pose[m].t);
        costs[m].push_back(cost);
        if (m > 0 && cost > base * (1.0 + 1e-9)) ++above[m];
        worst[m] = std::max(worst[m], (cost - base) / base);
      }
      if (p == 0) {
        for (int m = 0; m < 4; ++m) {
          char line[512];
          std::snprintf(line, sizeof line,
                        "N = %4d %-24s t = (%+.9f, %+.9f, %+.9f)  R row 0 = (%+.9f, %+.9f, %+.9f)  cost %.6f",
                        n, names[m], pose[m].t[0], pose[m].t[1], pose[m].t[2], pose[m].r[0], pose[m].r[1],
                        pose[m].r[2], costs[m].back());
          poses.emplace_back(line);
        }
      }
    }
    for (int m = 0; m < 4; ++m) {
      char cmp[64] = "-", diff[64] = "-";
      if (m > 0) {
        std::snprintf(cmp, sizeof cmp, "%d of %d", above[m], problems);
        std::snprintf(diff, sizeof diff, "%+.1e", worst[m]);
      }
      std::printf("| %d | %s | %.2f | %.4f | %s | %s |\n", n, names[m], median(times[m]), median(costs[m]), cmp,
                  diff);
    }
    std::printf("| %d | speed-up of eopnp: %.1fx ITERATIVE, %.1fx SQPNP | | | | |\n", n,
                median(times[0]) / median(times[2]), median(times[1]) / median(times[2]));
  }
  std::printf("\nposes of the first problem of each N (x_cam = R X + t):\n");
  for (const auto& l : poses) std::printf("%s\n", l.c_str());
  return 0;
}
