// The C++ interface (eopnp.hpp): RAII handles, the exception hierarchy, the span and pointer
// overloads, the poses equal to the Rust library's bit for bit (the reference file of the C
// test), and, when built with OpenCV, the cv::solvePnP-shaped overloads.
//
// Usage: test_cpp REFERENCE_FILE COLMAP_MODEL_DIR COLMAP_RIG_MODEL_DIR
#ifdef EOPNP_TEST_OPENCV
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#endif
#include "eopnp.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

static int failures = 0;
static int checks = 0;

#define CHECK(cond)                                                                  \
  do {                                                                               \
    ++checks;                                                                        \
    if (!(cond)) {                                                                   \
      ++failures;                                                                    \
      std::cerr << __FILE__ << ":" << __LINE__ << ": CHECK failed: " #cond "\n";     \
    }                                                                                \
  } while (0)

// `expr` throws exactly `Type` (checked also as an eopnp::Error with that status).
#define THROWS(Type, status_, expr)                                                           \
  do {                                                                                        \
    ++checks;                                                                                 \
    bool caught_ = false;                                                                     \
    try {                                                                                     \
      (void)(expr);                                                                           \
    } catch (const Type& e_) {                                                                \
      const eopnp::Error& base_ = e_;                                                         \
      caught_ = base_.status() == (status_) && std::string(base_.what()).size() > 0;          \
    } catch (const std::exception& e_) {                                                      \
      std::cerr << __FILE__ << ":" << __LINE__ << ": other exception: " << e_.what() << "\n"; \
    }                                                                                         \
    if (!caught_) {                                                                           \
      ++failures;                                                                             \
      std::cerr << __FILE__ << ":" << __LINE__ << ": " #expr " did not throw " #Type "\n";    \
    }                                                                                         \
  } while (0)

static_assert(std::is_base_of<std::runtime_error, eopnp::Error>::value, "one hierarchy");
static_assert(std::is_base_of<eopnp::Error, eopnp::DegenerateError>::value, "one hierarchy");
static_assert(!std::is_copy_constructible<eopnp::Solver>::value, "handles are not copied");
static_assert(std::is_nothrow_move_constructible<eopnp::Solver>::value, "handles move");

namespace {

double from_hex(const std::string& s) {
  const unsigned long long b = std::stoull(s, nullptr, 16);
  double d;
  std::memcpy(&d, &b, sizeof d);
  return d;
}

std::vector<double> read_line(std::istream& in, const char* name, std::size_t n) {
  std::string word;
  in >> word;
  if (word != name) throw std::runtime_error(std::string("reference: expected ") + name);
  std::vector<double> v(n);
  for (double& x : v) {
    in >> word;
    x = from_hex(word);
  }
  return v;
}

// The reference cases through the C++ interface (the options as in the C test).
void test_reference(const std::string& path) {
  std::ifstream in(path);
  CHECK(in.good());
  const std::vector<double> colmap = {800.0, 810.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -5e-4};
  const double k[9] = {800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0};
  const double dist[5] = {-0.1, 0.02, 1e-3, -5e-4, 0.001};
  const eopnp::Camera colmap_cam = eopnp::Camera::colmap("OPENCV", 640, 480, colmap);
  const eopnp::Camera opencv_cam = eopnp::Camera::opencv(k, dist, 5);
  // The cameras describe themselves: COLMAP's name, size, parameters.
  CHECK(colmap_cam.model_name() == "OPENCV" && colmap_cam.params() == colmap);
  CHECK(colmap_cam.info().width == 640 && colmap_cam.info().height == 480);
  const std::vector<double> full = opencv_cam.params();
  CHECK(opencv_cam.model_name() == "FULL_OPENCV" && full.size() == 12);
  CHECK(full[0] == 800.0 && full[1] == 810.0 && full[4] == -0.1 && full[8] == 0.001);
  CHECK(full[9] == 0.0 && full[11] == 0.0 && opencv_cam.info().fy == 810.0);
  int cases = 0, equal = 0;
  std::string word;
  while (in >> word) {
    int kind = 0;
    std::size_t n = 0;
    in >> kind >> n;
    const auto world = read_line(in, "world", 3 * n);
    const auto image = read_line(in, "image", 2 * n);
    const auto weights = read_line(in, "weights", n);
    const auto prior = read_line(in, "prior", 12);
    const auto rotation = read_line(in, "rotation", 9);
    const auto translation = read_line(in, "translation", 3);
    const auto cost = read_line(in, "cost", 1);
    const auto covariance = read_line(in, "covariance", 36);
    in >> word;
    std::vector<std::uint8_t> mask(n);
    for (auto& m : mask) {
      int x;
      in >> x;
      m = static_cast<std::uint8_t>(x);
    }
    ++cases;
    eopnp::Solver solver;
    eopnp::Problem p = eopnp::Problem::normalised(world.data(), image.data(), n);
    if (kind == 1 || kind == 2) p = eopnp::Problem::pixels(world.data(), image.data(), n, colmap_cam);
    if (kind == 6) p = eopnp::Problem::pixels(world.data(), image.data(), n, opencv_cam);
    std::vector<std::uint8_t> got_mask(n, 1);
    eopnp::Solution s{};
    switch (kind) {
      case 2:
        p.weights(weights.data());
        solver.loss(EOPNP_LOSS_HUBER, 2.0).covariance(EOPNP_COVARIANCE_SIGMA, 1.0);
        s = solver.solve(p);
        break;
      case 3:
        s = solver.refinement(EOPNP_REFINEMENT_ALGEBRAIC).solve(p);
        break;
      case 4: {
        eopnp::Pose pose{};
        std::memcpy(pose.rotation, prior.data(), sizeof pose.rotation);
        std::memcpy(pose.translation, prior.data() + 9, sizeof pose.translation);
        s = solver.refine(p, pose);
        break;
      }
      case 5: {
        p.focal(800.0, 800.0);
        const auto r = eopnp::Ransac().threshold_px(2.0).seed(9).estimate(solver, p);
        s = r.solution;
        got_mask = r.inliers;
        break;
      }
      default:
        s = solver.solve(p);
    }
    const bool ok = std::memcmp(s.rotation, rotation.data(), sizeof s.rotation) == 0 &&
                    std::memcmp(s.translation, translation.data(), sizeof s.translation) == 0 &&
                    std::memcmp(&s.cost, cost.data(), sizeof s.cost) == 0 &&
                    std::memcmp(s.covariance, covariance.data(), sizeof s.covariance) == 0 &&
                    got_mask == mask;
    CHECK(ok);
    equal += ok;
  }
  CHECK(cases == 21);
  std::printf("reference: %d of %d cases equal to the Rust library's bit for bit\n", equal, cases);
}

constexpr std::size_t N = 12;
double W[3 * N], M[2 * N], PX[2 * N];

void make_problem() {
  for (std::size_t i = 0; i < N; ++i) {
    const double x = -1.0 + 0.37 * (i % 6), y = -0.8 + 0.5 * ((3 * i) % 4),
                 z = 0.3 * ((2 * i) % 5) - 0.6;
    W[3 * i] = x;
    W[3 * i + 1] = y;
    W[3 * i + 2] = z;
    const double cx = x + 0.1, cy = y - 0.2, cz = z + 6.0;
    M[2 * i] = cx / cz;
    M[2 * i + 1] = cy / cz;
    PX[2 * i] = 800.0 * cx / cz + 320.0;
    PX[2 * i + 1] = 800.0 * cy / cz + 240.0;
  }
}

// The known vertical and the unknown focal length (Problem::gravity, Problem::unknown_focal,
// estimated_focal, GravityMismatchError). The problem's pose is R = I.
void test_focal_and_gravity() {
  const eopnp::Solver solver;
  const auto guess = eopnp::Camera::pinhole(1100.0, 1100.0, 320.0, 240.0);
  // Known focal length: nothing estimated, a poor fit.
  const auto plain = solver.solve(eopnp::Problem::pixels(W, PX, N, guess));
  CHECK(!eopnp::estimated_focal(plain).has_value());
  CHECK(plain.reprojection_rmse * 1100.0 > 1.0);
  // Unknown: 800 px from 1100.
  const auto s = solver.solve(eopnp::Problem::pixels(W, PX, N, guess).unknown_focal());
  const auto f = eopnp::estimated_focal(s);
  CHECK(f.has_value() && std::fabs((*f)[0] - 800.0) < 1e-6 && std::fabs((*f)[1] - 800.0) < 1e-6);
  CHECK(std::fabs(s.translation[2] - 6.0) < 1e-6);
  const auto r = solver.solve(eopnp::Problem::pixels(W, PX, N, guess).unknown_focal(500.0, 2000.0));
  CHECK(r.focal_estimated && std::fabs(r.focal_x - 800.0) < 1e-6);
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::pixels(W, PX, N, guess).unknown_focal(2000.0, 500.0)));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::normalised(W, M, N).unknown_focal()));

  // The vertical: copied into the problem, so the problem (and its copies) outlive the arrays.
  eopnp::Problem g = eopnp::Problem::normalised(W, M, N);
  {
    const std::array<double, 3> down = {0.0, 0.0, -1.0};
    g.gravity(down, down, 0.5);
  }
  const eopnp::Problem copy = g;
  const auto v = solver.solve(copy);
  CHECK(std::fabs(v.rotation[0] - 1.0) < 1e-9 && std::fabs(v.translation[2] - 6.0) < 1e-9);
  CHECK(copy.c().gravity_camera != g.c().gravity_camera);  // each points at its own copy
  const double deg = 3.14159265358979323846 / 180.0;
  const std::array<double, 3> tilted = {0.0, std::sin(10.0 * deg), -std::cos(10.0 * deg)};
  ++checks;
  try {
    (void)solver.solve(eopnp::Problem::normalised(W, M, N).gravity(tilted, {0.0, 0.0, -1.0}, 0.1));
    ++failures;
    std::cerr << __FILE__ << ":" << __LINE__ << ": no GravityMismatchError\n";
  } catch (const eopnp::GravityMismatchError& e) {
    const std::string what = e.what();
    double angle = 0.0;
    const auto at = what.find(" is ");
    if (at == std::string::npos ||
        std::sscanf(what.c_str() + at, " is %lf degrees off", &angle) != 1 ||
        std::fabs(angle - 10.0) > 0.1 || e.status() != EOPNP_GRAVITY_MISMATCH) {
      ++failures;
      std::cerr << __FILE__ << ":" << __LINE__ << ": unexpected mismatch: " << what << "\n";
    }
  }
  const std::array<double, 3> down = {0.0, 0.0, -1.0}, zero = {0.0, 0.0, 0.0};
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::normalised(W, M, N).gravity(down, down, 0.0)));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::normalised(W, M, N).gravity(zero, down, 1.0)));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::pixels(W, PX, N, guess).gravity(down, down, 1.0).unknown_focal()));
}

// The refined principal point and distortion (Problem::refine_principal_point,
// Problem::refine_distortion, estimated_camera_params): a SIMPLE_RADIAL camera recovered from a
// guess with its principal point off and no distortion, on 30 points over a wide field of
// view (pose R = I, t = (0.1, -0.2, 0.3)).
void test_refined_intrinsics() {
  constexpr std::size_t n = 30;
  const std::array<double, 4> truth = {500.0, 318.0, 243.0, -0.08};  // f, cx, cy, k
  std::vector<double> w(3 * n), px(2 * n), m(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = -2.0 + 0.8 * (i % 6), y = -1.5 + 0.75 * ((i / 6) % 5);
    const double z = 4.0 + 0.4 * ((7 * i) % 11);
    w[3 * i] = x - 0.1;
    w[3 * i + 1] = y + 0.2;
    w[3 * i + 2] = z - 0.3;
    const double u = x / z, v = y / z, d = 1.0 + truth[3] * (u * u + v * v);
    m[2 * i] = u;
    m[2 * i + 1] = v;
    px[2 * i] = truth[0] * d * u + truth[1];
    px[2 * i + 1] = truth[0] * d * v + truth[2];
  }
  const eopnp::Solver solver;
  const auto guess = eopnp::Camera::colmap("SIMPLE_RADIAL", 640, 480, {500.0, 325.0, 236.0, 0.0});
  const auto guess_f = eopnp::Camera::colmap("SIMPLE_RADIAL", 640, 480, {650.0, 325.0, 236.0, 0.0});
  const auto plain = solver.solve(eopnp::Problem::pixels(w.data(), px.data(), n, guess));
  CHECK(!eopnp::estimated_camera_params(plain).has_value());
  CHECK(plain.cost > 1.0);
  const auto s = solver.solve(
      eopnp::Problem::pixels(w.data(), px.data(), n, guess).refine_principal_point().refine_distortion());
  const auto cam = eopnp::estimated_camera_params(s);
  CHECK(cam.has_value() && cam->size() == 4);
  CHECK(!eopnp::estimated_focal(s).has_value());
  if (cam && cam->size() == 4) {
    CHECK((*cam)[0] == 500.0);
    for (std::size_t j = 1; j < 4; ++j) CHECK(std::fabs((*cam)[j] - truth[j]) < 1e-6);
  }
  CHECK(std::fabs(s.translation[2] - 0.3) < 1e-6);
  const auto all = solver.solve(eopnp::Problem::pixels(w.data(), px.data(), n, guess_f)
                                    .unknown_focal()
                                    .refine_principal_point()
                                    .refine_distortion());
  const auto f = eopnp::estimated_focal(all);
  const auto cam_f = eopnp::estimated_camera_params(all);
  CHECK(f.has_value() && cam_f.has_value() && cam_f->size() == 4);
  if (f && cam_f && cam_f->size() == 4) {
    CHECK((*f)[0] == (*cam_f)[0]);
    for (std::size_t j = 0; j < 4; ++j) CHECK(std::fabs((*cam_f)[j] - truth[j]) < 1e-6);
  }
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::normalised(w.data(), m.data(), n).refine_distortion()));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         solver.solve(eopnp::Problem::pixels(w.data(), px.data(), n, guess)
                          .gravity({0.0, 1.0, 0.0}, {0.0, 1.0, 0.0}, 1.0)
                          .refine_principal_point()));
  THROWS(eopnp::TooFewPointsError, EOPNP_TOO_FEW_POINTS,
         solver.solve(eopnp::Problem::pixels(w.data(), px.data(), 4, guess_f)
                          .unknown_focal()
                          .refine_principal_point()
                          .refine_distortion()));
}

void test_frames(const std::string& dir) {
  const auto model = eopnp::Model::read(dir);
  const auto ids = model.frame_ids();
  CHECK(ids.size() == 6);
  const eopnp::Solver solver;
  const auto f = model.register_frame(ids[0], solver);
  CHECK(f.frame_id == ids[0] && f.images >= 2 && f.rotation_error_deg < 1.0);
  THROWS(eopnp::RegisterError, EOPNP_REGISTER_ERROR, model.register_frame(4242, solver));
}

void test_interface(const std::string& model_dir) {
  eopnp::Solver solver;
  const auto cam = eopnp::Camera::pinhole(800.0, 800.0, 320.0, 240.0);
  const auto s = solver.solve(eopnp::Problem::pixels(W, PX, N, cam));
  CHECK(std::fabs(s.translation[2] - 6.0) < 1e-9);
  const auto px = cam.project(M[0], M[1]);
  CHECK(std::fabs(px[0] - PX[0]) < 1e-9);
  const auto back = cam.undistort(px[0], px[1]);
  CHECK(std::fabs(back[1] - M[1]) < 1e-12);

  // Moves keep the handle.
  eopnp::Solver moved = std::move(solver);
  CHECK(moved.get() != nullptr && solver.get() == nullptr);
  const auto again = moved.solve(eopnp::Problem::normalised(W, M, N));
  CHECK(std::fabs(again.translation[2] - 6.0) < 1e-9);

  // Every minimum, refinement, RANSAC, batch, rig.
  CHECK(!moved.solve_all(eopnp::Problem::normalised(W, M, 4)).empty());
  eopnp::Pose prior{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0.1, -0.1, 5.5}};
  CHECK(std::fabs(moved.refine(eopnp::Problem::normalised(W, M, N), prior).translation[2] - 6.0) < 1e-9);
  const auto r = eopnp::Ransac().threshold_px(2.0).estimate(moved, eopnp::Problem::pixels(W, PX, N, cam));
  CHECK(r.stats.inliers == N && r.inliers.size() == N);
  std::vector<eopnp::Status> statuses;
  const auto batch = moved.solve_batch(
      {eopnp::Problem::normalised(W, M, N), eopnp::Problem::normalised(W, M, 3)}, 2, statuses);
  CHECK(batch.size() == 2 && statuses[0] == EOPNP_OK && statuses[1] == EOPNP_TOO_FEW_POINTS);
  const eopnp::Camera* cams[1] = {&cam};
  const eopnp::Pose identity{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}};
  const eopnp::Rig rig(cams, &identity, 1);
  const std::vector<std::uint32_t> which(N, 0);
  CHECK(std::fabs(moved.solve(eopnp::Problem::rig(W, PX, which.data(), N, rig)).translation[2] - 6.0) < 1e-9);

  // Exceptions: one class per status, all eopnp::Error.
  THROWS(eopnp::TooFewPointsError, EOPNP_TOO_FEW_POINTS, moved.solve(eopnp::Problem::normalised(W, M, 3)));
  THROWS(eopnp::NullPointerError, EOPNP_NULL_POINTER, moved.solve(eopnp::Problem::normalised(nullptr, M, N)));
  double w2[3 * N];
  std::memcpy(w2, W, sizeof W);
  w2[4] = NAN;
  THROWS(eopnp::NonFiniteError, EOPNP_NON_FINITE, moved.solve(eopnp::Problem::normalised(w2, M, N)));
  try {
    moved.solve(eopnp::Problem::normalised(w2, M, N));
  } catch (const eopnp::NonFiniteError& e) {
    CHECK(e.info().index == 1 && e.info().input == EOPNP_INPUT_WORLD);
  }
  std::vector<double> neg(N, 1.0);
  neg[3] = -1.0;
  THROWS(eopnp::InvalidWeightError, EOPNP_INVALID_WEIGHT,
         moved.solve(eopnp::Problem::normalised(W, M, N).weights(neg.data())));
  std::vector<double> line(3 * N);
  for (std::size_t i = 0; i < N; ++i) line[3 * i] = static_cast<double>(i);
  THROWS(eopnp::DegenerateError, EOPNP_DEGENERATE, moved.solve(eopnp::Problem::normalised(line.data(), M, N)));
  THROWS(eopnp::InvalidArgumentError, EOPNP_INVALID_ARGUMENT,
         moved.solve(eopnp::Problem::normalised(W, M, N).strides(1, 0)));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION, eopnp::Solver().loss(EOPNP_LOSS_CAUCHY, -1.0));
  THROWS(eopnp::InvalidArgumentError, EOPNP_INVALID_ARGUMENT,
         eopnp::Solver().refinement(static_cast<EopnpRefinement>(5)));
  THROWS(eopnp::CameraError, EOPNP_CAMERA_ERROR, eopnp::Camera::colmap("NOPE", 1, 1, {1.0}));
  THROWS(eopnp::CameraError, EOPNP_CAMERA_ERROR, eopnp::Camera::colmap("PINHOLE", 1, 1, {1.0}));
  THROWS(eopnp::UnknownCameraError, EOPNP_UNKNOWN_CAMERA,
         moved.solve(eopnp::Problem::rig(W, PX, std::vector<std::uint32_t>(N, 1).data(), N, rig)));
  THROWS(eopnp::LengthMismatchError, EOPNP_LENGTH_MISMATCH,
         eopnp::Rig(std::vector<const eopnp::Camera*>{&cam}, std::vector<eopnp::Pose>{}));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         eopnp::Ransac().confidence(2.0).estimate(moved, eopnp::Problem::pixels(W, PX, N, cam)));
  std::vector<double> scrambled(2 * N);
  for (std::size_t i = 0; i < N; ++i) {
    scrambled[2 * i] = PX[2 * ((i * 5) % N)];
    scrambled[2 * i + 1] = PX[2 * ((i * 7 + 3) % N) + 1];
  }
  THROWS(eopnp::NoConsensusError, EOPNP_NO_CONSENSUS,
         eopnp::Ransac().estimate(moved, eopnp::Problem::pixels(W, scrambled.data(), N, cam)));
  THROWS(eopnp::ModelError, EOPNP_MODEL_ERROR, eopnp::Model::read("/nonexistent/eopnp-model"));

#ifdef EOPNP_HAS_SPAN
  // Spans: sizes checked on the C++ side.
  const std::vector<double> wv(W, W + 3 * N), mv(M, M + 2 * N);
  CHECK(std::fabs(moved.solve(eopnp::Problem::normalised(std::span<const double>(wv), std::span<const double>(mv))).translation[2] - 6.0) < 1e-9);
  THROWS(eopnp::LengthMismatchError, EOPNP_LENGTH_MISMATCH,
         eopnp::Problem::normalised(std::span<const double>(wv).first(3 * N - 3), std::span<const double>(mv)));
  auto sp = eopnp::Problem::normalised(std::span<const double>(wv), std::span<const double>(mv));
  THROWS(eopnp::WeightsLengthError, EOPNP_WEIGHTS_LENGTH, sp.weights(std::span<const double>(neg).first(2)));
  std::printf("span overloads tested (C++20)\n");
#endif

  // COLMAP.
  const auto model = eopnp::Model::read(model_dir);
  const auto ids = model.image_ids();
  CHECK(ids.size() == 6);
  const eopnp::Ransac ransac;
  const auto reg = model.register_image(ids[0], moved, &ransac);
  CHECK(reg.has_ransac && reg.rotation_error_deg < 1.0);
  (void)model.camera(1);
  THROWS(eopnp::RegisterError, EOPNP_REGISTER_ERROR, model.register_image(99999, moved));
  std::vector<std::uint32_t> with_bad = ids;
  with_bad.push_back(99999);
  std::vector<eopnp::Status> reg_statuses;
  const auto regs = model.register_batch(with_bad, moved, &ransac, 2, reg_statuses);
  CHECK(regs.size() == 7 && reg_statuses[6] == EOPNP_REGISTER_ERROR);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    CHECK(reg_statuses[i] == EOPNP_OK && regs[i].image_id == ids[i]);
    // The same as one registration at a time (RANSAC's seed does not depend on the batch).
    const auto one = model.register_image(ids[i], moved, &ransac);
    CHECK(std::memcmp(one.solution.rotation, regs[i].solution.rotation, sizeof one.solution.rotation) == 0);
  }
  // Free intrinsics (FreeIntrinsics): the focal length re-estimated from the model camera's.
  const auto focal = eopnp::FreeIntrinsics().unknown_focal();
  const auto fr = model.register_image(ids[0], moved, nullptr, focal);
  const auto fe = eopnp::focal_error_pct(fr);
  CHECK(fe.has_value() && *fe >= 0.0 && *fe < 0.01 && fr.rotation_error_deg < 0.01);
  const auto ff = eopnp::estimated_focal(fr.solution);
  const auto fc = eopnp::estimated_camera_params(fr.solution);
  CHECK(ff.has_value() && fc.has_value() && fc->size() == 4 && (*fc)[0] == (*ff)[0]);
  CHECK(!eopnp::focal_error_pct(model.register_image(ids[0], moved)).has_value());
  const auto dist = model.register_image(ids[0], moved, &ransac, eopnp::FreeIntrinsics().refine_distortion());
  CHECK(eopnp::focal_error_pct(dist) == std::optional<double>(0.0));
  CHECK(!eopnp::estimated_focal(dist.solution).has_value() && eopnp::estimated_camera_params(dist.solution));
  THROWS(eopnp::InvalidOptionError, EOPNP_INVALID_OPTION,
         model.register_image(ids[0], moved, nullptr, eopnp::FreeIntrinsics().unknown_focal(2000.0, 1000.0)));
  std::vector<eopnp::Status> f_statuses;
  const auto fregs = model.register_batch(ids, moved, nullptr, 2, f_statuses, focal);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const auto one = model.register_image(ids[i], moved, nullptr, focal);
    CHECK(f_statuses[i] == EOPNP_OK && fregs[i].has_focal_error);
    CHECK(std::memcmp(&one.focal_error_pct, &fregs[i].focal_error_pct, sizeof one.focal_error_pct) == 0);
    CHECK(std::memcmp(one.solution.translation, fregs[i].solution.translation,
                      sizeof one.solution.translation) == 0);
  }
  // RANSAC batches: problem i with the seed problem_seed(seed, i); an invalid problem's status.
  std::vector<eopnp::Status> r_statuses;
  const auto rs = ransac.estimate_batch(
      moved, {eopnp::Problem::pixels(W, PX, N, cam), eopnp::Problem::pixels(W, PX, 2, cam)}, 2, r_statuses);
  CHECK(rs.size() == 2 && r_statuses[0] == EOPNP_OK && r_statuses[1] == EOPNP_TOO_FEW_POINTS);
  CHECK(rs[0].stats.inliers == N && rs[0].inliers.size() == N && rs[0].inliers[N - 1] == 1);

  // Threads: one solver, several threads, each with its own last error.
  std::vector<std::thread> threads;
  std::vector<int> errors(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 100; ++i) {
        try {
          moved.solve(eopnp::Problem::normalised(W, M, static_cast<std::size_t>(t)));
          ++errors[t];
        } catch (const eopnp::TooFewPointsError& e) {
          if (e.info().got != static_cast<std::uint64_t>(t)) ++errors[t];
        }
        if (std::fabs(moved.solve(eopnp::Problem::normalised(W, M, N)).translation[2] - 6.0) > 1e-9)
          ++errors[t];
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int e : errors) CHECK(e == 0);
}

#ifdef EOPNP_TEST_OPENCV
void test_opencv() {
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (std::size_t i = 0; i < N; ++i) {
    obj.emplace_back(W[3 * i], W[3 * i + 1], W[3 * i + 2]);
    img.emplace_back(PX[2 * i], PX[2 * i + 1]);
  }
  const cv::Mat k = (cv::Mat_<double>(3, 3) << 800, 0, 320, 0, 800, 240, 0, 0, 1);
  const cv::Mat dist;
  cv::Mat rvec, tvec, rvec_cv, tvec_cv;
  CHECK(eopnp::cv::solvePnP(obj, img, k, dist, rvec, tvec));
  CHECK(cv::solvePnP(obj, img, k, dist, rvec_cv, tvec_cv, false, cv::SOLVEPNP_ITERATIVE));
  CHECK(rvec.rows == 3 && rvec.cols == 1 && rvec.type() == CV_64F && tvec.type() == CV_64F);
  CHECK(cv::norm(tvec - tvec_cv) < 1e-6 && cv::norm(rvec - rvec_cv) < 1e-6);
  CHECK(std::fabs(tvec.at<double>(2) - 6.0) < 1e-9);
  // Float points and a distortion vector, as OpenCV accepts them.
  std::vector<cv::Point3f> objf(obj.begin(), obj.end());
  std::vector<cv::Point2f> imgf(img.begin(), img.end());
  CHECK(eopnp::cv::solvePnP(objf, imgf, k, std::vector<double>{0, 0, 0, 0}, rvec, tvec));
  CHECK(std::fabs(tvec.at<double>(2) - 6.0) < 1e-4);
  // The prior pose (useExtrinsicGuess).
  cv::Mat r0 = (cv::Mat_<double>(3, 1) << 0.01, -0.01, 0.02), t0 = (cv::Mat_<double>(3, 1) << 0.1, -0.1, 5.5);
  CHECK(eopnp::cv::solvePnP(obj, img, k, dist, r0, t0, true));
  CHECK(std::fabs(t0.at<double>(2) - 6.0) < 1e-9);
  // RANSAC with inlier indices; an outlier.
  img[3].x += 50.0;
  std::vector<int> inliers;
  CHECK(eopnp::cv::solvePnPRansac(obj, img, k, dist, rvec, tvec, false, 100, 2.0f, 0.99, inliers));
  CHECK(inliers.size() == N - 1 && std::find(inliers.begin(), inliers.end(), 3) == inliers.end());
  // Bad input: different counts, the wrong shape of K.
  img.pop_back();
  THROWS(eopnp::LengthMismatchError, EOPNP_LENGTH_MISMATCH, eopnp::cv::solvePnP(obj, img, k, dist, rvec, tvec));
  THROWS(eopnp::InvalidArgumentError, EOPNP_INVALID_ARGUMENT,
         eopnp::cv::solvePnP(obj, obj, k, dist, rvec, tvec));
  img.emplace_back(PX[2 * (N - 1)], PX[2 * (N - 1) + 1]);
  THROWS(eopnp::InvalidArgumentError, EOPNP_INVALID_ARGUMENT,
         eopnp::cv::solvePnP(obj, img, cv::Mat::eye(2, 2, CV_64F), dist, rvec, tvec));
  std::printf("OpenCV overloads tested (OpenCV %s)\n", CV_VERSION);
}
#endif

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s REFERENCE_FILE COLMAP_MODEL_DIR COLMAP_RIG_MODEL_DIR\n", argv[0]);
    return 2;
  }
  make_problem();
  try {
    test_interface(argv[2]);
    test_frames(argv[3]);
    test_focal_and_gravity();
    test_refined_intrinsics();
#ifdef EOPNP_TEST_OPENCV
    test_opencv();
#endif
    test_reference(argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "unexpected exception: " << e.what() << "\n";
    return 1;
  }
  std::printf("%d checks, %d failed\n", checks, failures);
  return failures == 0 ? 0 : 1;
}
