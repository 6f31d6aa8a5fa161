// eopnp.hpp: the C++ interface of eopnp (camera pose from 2D-3D correspondences: EOPnP and the
// maximum-likelihood Levenberg-Marquardt refinement), header-only over the C interface
// eopnp.h. C++17; std::span overloads under C++20.
//
// - RAII handles (Solver, Ransac, Camera, Rig, Model): movable, not copyable; each owns its C
//   handle and frees it.
// - Errors are exceptions of one hierarchy rooted at eopnp::Error (a std::runtime_error),
//   one class per status, mirroring the Rust library's PnpError (TooFewPointsError,
//   NonFiniteError, DegenerateError, ...); Error::status() and Error::info() give the details.
// - Poses map world to camera, x_cam = R X + t; rotations are row-major 3 x 3 (std::array of 9).
// - Problem is a view: it borrows the caller's arrays (and camera or rig), which must outlive
//   every call that uses it; it copies nothing.
// - Thread safety: as the C interface. Solving is const and may run on several threads with the
//   same Solver / Ransac / Camera / Rig; the setters must not run concurrently with a solve.
//
// OpenCV: when <opencv2/core.hpp> was included before this header (or EOPNP_WITH_OPENCV is
// defined), eopnp::cv::solvePnP and eopnp::cv::solvePnPRansac are shaped like OpenCV's
// (cv::InputArray points, K, distortion, rvec/tvec out), so that a call site switches by
// changing the namespace.
#ifndef EOPNP_HPP
#define EOPNP_HPP

#include "eopnp.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#if __cplusplus >= 202002L && defined(__has_include)
#if __has_include(<span>)
#include <span>
#define EOPNP_HAS_SPAN 1
#endif
#endif

namespace eopnp {

/// A solved pose and its diagnostics (the C struct: rotation row-major, translation, cost, ...).
using Solution = EopnpSolution;
/// A pose x_cam = R X + t (rotation row-major), the input of Solver::refine and of rigs.
using Pose = EopnpPose;
/// RANSAC's statistics.
using RansacStats = EopnpRansacStats;
/// The registration of one image of a COLMAP model.
using Registration = EopnpRegistration;
/// The registration of one frame of a COLMAP model with rigs.
using FrameRegistration = EopnpFrameRegistration;
/// The status codes.
using Status = EopnpStatus;

// -------------------------------------------------------------------------------------------
// Errors.

/// The root of every exception this interface throws: the status and the message of the
/// failed call, and its details (EopnpErrorInfo: index, input, degenerate kind, counts).
class Error : public std::runtime_error {
 public:
  Error(EopnpStatus status, const std::string& message, const EopnpErrorInfo& info)
      : std::runtime_error(message), status_(status), info_(info) {}
  /// The C status of the failure.
  EopnpStatus status() const noexcept { return status_; }
  /// The failure's details.
  const EopnpErrorInfo& info() const noexcept { return info_; }

 private:
  EopnpStatus status_;
  EopnpErrorInfo info_;
};

#define EOPNP_ERROR_CLASS(Name)            \
  class Name : public Error {              \
   public:                                 \
    using Error::Error;                    \
  };
/// A NULL pointer reached the C interface (EOPNP_NULL_POINTER).
EOPNP_ERROR_CLASS(NullPointerError)
/// An argument out of range: a stride, a size, an enumeration value (EOPNP_INVALID_ARGUMENT).
EOPNP_ERROR_CLASS(InvalidArgumentError)
/// PnpError::TooFewPoints.
EOPNP_ERROR_CLASS(TooFewPointsError)
/// PnpError::LengthMismatch (also thrown by the span overloads for arrays of different counts).
EOPNP_ERROR_CLASS(LengthMismatchError)
/// PnpError::WeightsLength.
EOPNP_ERROR_CLASS(WeightsLengthError)
/// PnpError::NonFinite (info().index, info().input).
EOPNP_ERROR_CLASS(NonFiniteError)
/// PnpError::CameraIndicesLength.
EOPNP_ERROR_CLASS(CameraIndicesLengthError)
/// PnpError::UnknownCamera.
EOPNP_ERROR_CLASS(UnknownCameraError)
/// PnpError::InvalidWeight.
EOPNP_ERROR_CLASS(InvalidWeightError)
/// PnpError::Degenerate (info().degenerate).
EOPNP_ERROR_CLASS(DegenerateError)
/// PnpError::NoSolution.
EOPNP_ERROR_CLASS(NoSolutionError)
/// PnpError::InvalidOption.
EOPNP_ERROR_CLASS(InvalidOptionError)
/// PnpError::NoConsensus.
EOPNP_ERROR_CLASS(NoConsensusError)
/// A camera could not be built, or a point not projected or undistorted.
EOPNP_ERROR_CLASS(CameraError)
/// A COLMAP model could not be read.
EOPNP_ERROR_CLASS(ModelError)
/// PnpError::GravityMismatch: the images contradict the known vertical (Problem::gravity);
/// what() gives the angle in degrees and the distance in standard deviations.
EOPNP_ERROR_CLASS(GravityMismatchError)
/// A COLMAP image could not be registered (unknown image or camera).
EOPNP_ERROR_CLASS(RegisterError)
/// An output array too small.
EOPNP_ERROR_CLASS(BufferTooSmallError)
/// A panic caught at the C boundary (a bug of the library).
EOPNP_ERROR_CLASS(InternalError)
#undef EOPNP_ERROR_CLASS

namespace detail {

/// Throws the exception of `status`, with the calling thread's last error.
[[noreturn]] inline void throw_status(EopnpStatus status) {
  EopnpErrorInfo info{};
  eopnp_last_error(&info);
  const std::string msg = eopnp_last_error_message();
  switch (status) {
    case EOPNP_NULL_POINTER: throw NullPointerError(status, msg, info);
    case EOPNP_INVALID_ARGUMENT: throw InvalidArgumentError(status, msg, info);
    case EOPNP_TOO_FEW_POINTS: throw TooFewPointsError(status, msg, info);
    case EOPNP_LENGTH_MISMATCH: throw LengthMismatchError(status, msg, info);
    case EOPNP_WEIGHTS_LENGTH: throw WeightsLengthError(status, msg, info);
    case EOPNP_NON_FINITE: throw NonFiniteError(status, msg, info);
    case EOPNP_CAMERA_INDICES_LENGTH: throw CameraIndicesLengthError(status, msg, info);
    case EOPNP_UNKNOWN_CAMERA: throw UnknownCameraError(status, msg, info);
    case EOPNP_INVALID_WEIGHT: throw InvalidWeightError(status, msg, info);
    case EOPNP_DEGENERATE: throw DegenerateError(status, msg, info);
    case EOPNP_NO_SOLUTION: throw NoSolutionError(status, msg, info);
    case EOPNP_INVALID_OPTION: throw InvalidOptionError(status, msg, info);
    case EOPNP_NO_CONSENSUS: throw NoConsensusError(status, msg, info);
    case EOPNP_CAMERA_ERROR: throw CameraError(status, msg, info);
    case EOPNP_MODEL_ERROR: throw ModelError(status, msg, info);
    case EOPNP_REGISTER_ERROR: throw RegisterError(status, msg, info);
    case EOPNP_BUFFER_TOO_SMALL: throw BufferTooSmallError(status, msg, info);
    case EOPNP_PANIC: throw InternalError(status, msg, info);
    case EOPNP_GRAVITY_MISMATCH: throw GravityMismatchError(status, msg, info);
    default: throw Error(status, msg, info);
  }
}

inline void check(EopnpStatus status) {
  if (status != EOPNP_OK) throw_status(status);
}

/// A length mismatch found on the C++ side (span overloads).
[[noreturn]] inline void mismatch(const std::string& msg) {
  EopnpErrorInfo info{};
  info.status = EOPNP_LENGTH_MISMATCH;
  throw LengthMismatchError(EOPNP_LENGTH_MISMATCH, msg, info);
}

template <class T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const noexcept { Free(p); }
};

}  // namespace detail

// -------------------------------------------------------------------------------------------
// Cameras and rigs.

/// A camera model: COLMAP's models, OpenCV's K + distortion. Immutable; movable.
class Camera {
 public:
  /// A camera of a COLMAP model: its name ("PINHOLE", "OPENCV", ...), size in pixels and
  /// parameters in COLMAP's order (pixels in COLMAP's convention).
  static Camera colmap(const std::string& model, std::uint64_t width, std::uint64_t height,
                       const double* params, std::size_t n_params) {
    EopnpCamera* c = nullptr;
    detail::check(eopnp_camera_from_colmap(model.c_str(), width, height, params, n_params, &c));
    return Camera(c);
  }
  /// As above, the parameters in a vector.
  static Camera colmap(const std::string& model, std::uint64_t width, std::uint64_t height,
                       const std::vector<double>& params) {
    return colmap(model, width, height, params.data(), params.size());
  }
  /// OpenCV's intrinsics: K row-major (9 doubles), n_dist distortion coefficients (0, 4, 5, 8,
  /// 12 or 14); pixels in OpenCV's convention, as cv::solvePnP takes them.
  static Camera opencv(const double* k, const double* dist, std::size_t n_dist) {
    EopnpCamera* c = nullptr;
    detail::check(eopnp_camera_from_opencv(k, dist, n_dist, &c));
    return Camera(c);
  }
  /// OpenCV's fisheye model: K row-major, 4 coefficients.
  static Camera opencv_fisheye(const double* k, const double* dist4) {
    EopnpCamera* c = nullptr;
    detail::check(eopnp_camera_from_opencv_fisheye(k, dist4, &c));
    return Camera(c);
  }
  /// A pinhole camera (focal lengths and principal point in pixels).
  static Camera pinhole(double fx, double fy, double cx, double cy) {
    EopnpCamera* c = nullptr;
    detail::check(eopnp_camera_pinhole(fx, fy, cx, cy, &c));
    return Camera(c);
  }
  /// The pixel of a normalised image point (x/z, y/z).
  std::array<double, 2> project(double x, double y) const {
    const double in[2] = {x, y};
    std::array<double, 2> out{};
    detail::check(eopnp_camera_project(get(), in, out.data()));
    return out;
  }
  /// The normalised image point of a pixel.
  std::array<double, 2> undistort(double u, double v) const {
    const double in[2] = {u, v};
    std::array<double, 2> out{};
    detail::check(eopnp_camera_undistort(get(), in, out.data()));
    return out;
  }
  /// The camera's description: its model's COLMAP name, image size, parameter count and
  /// focal lengths.
  EopnpCameraInfo info() const {
    EopnpCameraInfo out{};
    detail::check(eopnp_camera_info(get(), &out));
    return out;
  }
  /// The model's COLMAP name ("SIMPLE_RADIAL", "OPENCV", ...).
  std::string model_name() const { return info().model; }
  /// The parameters, in the model's COLMAP order.
  std::vector<double> params() const {
    std::vector<double> out(info().n_params);
    std::size_t count = 0;
    detail::check(eopnp_camera_params(get(), out.data(), out.size(), &count));
    return out;
  }
  /// The C handle (owned by this object).
  const EopnpCamera* get() const noexcept { return h_.get(); }

 private:
  explicit Camera(EopnpCamera* c) : h_(c) {}
  friend class Model;
  std::unique_ptr<EopnpCamera, detail::Deleter<EopnpCamera, eopnp_camera_free>> h_;
};

/// A multi-camera rig: cameras (copied) and their poses in the rig, x_cam = R x_rig + t.
class Rig {
 public:
  /// `count` cameras and poses.
  Rig(const Camera* const* cameras, const Pose* cam_from_rig, std::size_t count) {
    std::vector<const EopnpCamera*> cs(count);
    for (std::size_t k = 0; k < count; ++k) cs[k] = cameras[k] ? cameras[k]->get() : nullptr;
    EopnpRig* r = nullptr;
    detail::check(eopnp_rig_create(cs.data(), cam_from_rig, count, &r));
    h_.reset(r);
  }
  /// Cameras and poses in vectors of the same length.
  Rig(const std::vector<const Camera*>& cameras, const std::vector<Pose>& cam_from_rig) {
    if (cameras.size() != cam_from_rig.size())
      detail::mismatch("a rig needs one pose per camera: " + std::to_string(cameras.size()) +
                       " cameras, " + std::to_string(cam_from_rig.size()) + " poses");
    *this = Rig(cameras.data(), cam_from_rig.data(), cameras.size());
  }
  /// The C handle (owned by this object).
  const EopnpRig* get() const noexcept { return h_.get(); }

 private:
  std::unique_ptr<EopnpRig, detail::Deleter<EopnpRig, eopnp_rig_free>> h_;
};

// -------------------------------------------------------------------------------------------
// Problems.

/// One pose problem: a view of the caller's arrays (world points x, y, z; image points x, y;
/// optional weights), like the Rust library's Problem. Nothing is copied: the arrays, and the
/// camera or rig, must outlive the calls that use the problem.
class Problem {
 public:
  /// `n` world points and their normalised image points (x/z, y/z), packed.
  static Problem normalised(const double* world, const double* image, std::size_t n) {
    Problem p;
    p.p_.n = n;
    p.p_.world = world;
    p.p_.image = image;
    return p;
  }
  /// `n` world points and the pixels where `camera` observed them, packed.
  static Problem pixels(const double* world, const double* pixels, std::size_t n,
                        const Camera& camera) {
    Problem p = normalised(world, pixels, n);
    p.p_.camera = camera.get();
    return p;
  }
  /// `n` world points and the pixels where the cameras of `rig` observed them: correspondence
  /// i in camera `cameras[i]`.
  static Problem rig(const double* world, const double* pixels, const std::uint32_t* cameras,
                     std::size_t n, const Rig& rig) {
    Problem p = normalised(world, pixels, n);
    p.p_.rig = rig.get();
    p.p_.rig_cameras = cameras;
    return p;
  }
#ifdef EOPNP_HAS_SPAN
  /// Spans of 3 n and 2 n doubles; other sizes throw LengthMismatchError.
  static Problem normalised(std::span<const double> world, std::span<const double> image) {
    return normalised(world.data(), image.data(), count(world, image));
  }
  /// Spans of 3 n and 2 n doubles; other sizes throw LengthMismatchError.
  static Problem pixels(std::span<const double> world, std::span<const double> pixels,
                        const Camera& camera) {
    return Problem::pixels(world.data(), pixels.data(), count(world, pixels), camera);
  }
  /// One non-negative weight per correspondence; another size throws WeightsLengthError.
  Problem& weights(std::span<const double> w) {
    if (w.size() != p_.n) {
      EopnpErrorInfo info{};
      info.status = EOPNP_WEIGHTS_LENGTH;
      throw WeightsLengthError(EOPNP_WEIGHTS_LENGTH,
                               "got " + std::to_string(w.size()) + " weights for " +
                                   std::to_string(p_.n) + " correspondences",
                               info);
    }
    return weights(w.data());
  }
#endif
  /// One non-negative weight per correspondence (`n` doubles), or nullptr for all 1.
  Problem& weights(const double* w) {
    p_.weights = w;
    return *this;
  }
  /// Strides of the arrays in doubles (0: packed).
  Problem& strides(std::size_t world_stride, std::size_t image_stride) {
    p_.world_stride = world_stride;
    p_.image_stride = image_stride;
    return *this;
  }
  /// Normalised input: the focal lengths in pixels that make RANSAC's threshold a pixel
  /// distance.
  Problem& focal(double fx, double fy) {
    p_.focal_x = fx;
    p_.focal_y = fy;
    return *this;
  }
  /// A known vertical: the direction of gravity (or any direction known in both frames)
  /// measured in the camera's (rig's) frame, the same direction in the world's frame (any
  /// non-zero lengths) and the measurement's standard deviation in degrees (finite, > 0). The
  /// solve returns the maximum a posteriori pose with it as a prior; images that contradict it
  /// throw GravityMismatchError, a zero direction or a bad sigma InvalidOptionError. The
  /// directions are copied into the problem.
  Problem& gravity(const std::array<double, 3>& in_camera, const std::array<double, 3>& in_world,
                   double sigma_deg) {
    gravity_camera_ = in_camera;
    gravity_world_ = in_world;
    has_gravity_ = true;
    p_.gravity_sigma_deg = sigma_deg;
    repoint();
    return *this;
  }
  /// Pixels through a camera only: the focal length is unknown and estimated with the pose, the
  /// camera's being the starting guess; sought between a tenth and ten times it, or between
  /// `min_px` and `max_px` (0 < min_px < max_px). The solution's focal_estimated, focal_x and
  /// focal_y give it (estimated_focal()), and camera_params the whole camera
  /// (estimated_camera_params()). Not with a vertical (InvalidOptionError).
  Problem& unknown_focal(double min_px = 0.0, double max_px = 0.0) {
    p_.unknown_focal = true;
    p_.focal_min_px = min_px;
    p_.focal_max_px = max_px;
    return *this;
  }
  /// Pixels through a camera only: the principal point is refined with the pose (and the focal
  /// length with unknown_focal()), the camera's being the starting guess (COLMAP's
  /// refine_principal_point; well determined only by many points over a wide field of view).
  /// estimated_camera_params() gives it. With normalised or rig input, or a vertical:
  /// InvalidOptionError.
  Problem& refine_principal_point() {
    p_.refine_principal_point = true;
    return *this;
  }
  /// Pixels through a camera only: the camera's distortion parameters (those after the
  /// principal point; none for the pinhole models) are refined with the pose, the camera's
  /// being the starting guess (COLMAP's refine_extra_params). estimated_camera_params() gives
  /// them. With normalised or rig input, or a vertical: InvalidOptionError.
  Problem& refine_distortion() {
    p_.refine_distortion = true;
    return *this;
  }
  /// The number of correspondences.
  std::size_t size() const noexcept { return p_.n; }
  /// The C problem.
  const EopnpProblem& c() const noexcept { return p_; }

  Problem(const Problem& o)
      : p_(o.p_), gravity_camera_(o.gravity_camera_), gravity_world_(o.gravity_world_),
        has_gravity_(o.has_gravity_) {
    repoint();
  }
  Problem& operator=(const Problem& o) {
    p_ = o.p_;
    gravity_camera_ = o.gravity_camera_;
    gravity_world_ = o.gravity_world_;
    has_gravity_ = o.has_gravity_;
    repoint();
    return *this;
  }

 private:
  Problem() : p_{} {}
  /// The C problem's vertical pointed at this object's copies.
  void repoint() noexcept {
    p_.gravity_camera = has_gravity_ ? gravity_camera_.data() : nullptr;
    p_.gravity_world = has_gravity_ ? gravity_world_.data() : nullptr;
  }
#ifdef EOPNP_HAS_SPAN
  static std::size_t count(std::span<const double> world, std::span<const double> image) {
    if (world.size() % 3 != 0 || image.size() % 2 != 0 || world.size() / 3 != image.size() / 2)
      detail::mismatch("world and image point counts differ (" + std::to_string(world.size()) +
                       " world coordinates, " + std::to_string(image.size()) +
                       " image coordinates); pass 3 per world point and 2 per image point");
    return world.size() / 3;
  }
#endif
  EopnpProblem p_;
  std::array<double, 3> gravity_camera_{};
  std::array<double, 3> gravity_world_{};
  bool has_gravity_ = false;
};

/// The focal lengths (fx, fy) a solution estimated (Problem::unknown_focal), or nothing when
/// the focal length was known (also with only the principal point or the distortion refined).
inline std::optional<std::array<double, 2>> estimated_focal(const Solution& s) {
  if (!s.focal_estimated) return std::nullopt;
  return std::array<double, 2>{s.focal_x, s.focal_y};
}

/// The parameters of the camera a solution estimated (Problem::unknown_focal,
/// refine_principal_point, refine_distortion), in the given camera's model's COLMAP order (as
/// Camera::params() gives them): the given camera with the free intrinsics replaced; nothing
/// when no intrinsic was free.
inline std::optional<std::vector<double>> estimated_camera_params(const Solution& s) {
  if (!s.camera_estimated) return std::nullopt;
  const std::size_t n =
      std::min<std::size_t>(s.camera_n_params, static_cast<std::size_t>(EOPNP_MAX_CAMERA_PARAMS));
  return std::vector<double>(s.camera_params, s.camera_params + n);
}

/// The intrinsics a registration re-estimates with the pose (Model::register_image,
/// Model::register_batch), the model's camera being the starting guess; the options of
/// Problem::unknown_focal, refine_principal_point and refine_distortion, with their rules and
/// exceptions. Nothing free by default:
///   model.register_image(id, solver, nullptr, eopnp::FreeIntrinsics().unknown_focal())
/// gives the estimated focal length in reg.solution (estimated_focal()) and its error against
/// the model camera's in focal_error_pct(reg).
class FreeIntrinsics {
 public:
  FreeIntrinsics() : f_{} {}
  /// The focal length is unknown: sought between a tenth and ten times the model camera's, or
  /// between `min_px` and `max_px` (0 < min_px < max_px, else InvalidOptionError).
  FreeIntrinsics& unknown_focal(double min_px = 0.0, double max_px = 0.0) {
    f_.unknown_focal = true;
    f_.focal_min_px = min_px;
    f_.focal_max_px = max_px;
    return *this;
  }
  /// The principal point is refined with the pose.
  FreeIntrinsics& refine_principal_point() {
    f_.refine_principal_point = true;
    return *this;
  }
  /// The distortion parameters are refined with the pose.
  FreeIntrinsics& refine_distortion() {
    f_.refine_distortion = true;
    return *this;
  }
  /// The C struct.
  const EopnpFreeIntrinsics& c() const noexcept { return f_; }

 private:
  EopnpFreeIntrinsics f_;
};

/// The estimated focal length's error against the model camera's, percent, of a registration
/// with free intrinsics (FreeIntrinsics); nothing through the model's camera.
inline std::optional<double> focal_error_pct(const Registration& r) {
  if (!r.has_focal_error) return std::nullopt;
  return r.focal_error_pct;
}

// -------------------------------------------------------------------------------------------
// Solver and RANSAC.

/// Solver options and the solves. The default is the recommended configuration.
class Solver {
 public:
  Solver() {
    EopnpSolver* s = nullptr;
    detail::check(eopnp_solver_create(&s));
    h_.reset(s);
  }
  /// Which cost the pose minimises.
  Solver& refinement(EopnpRefinement r) {
    detail::check(eopnp_solver_set_refinement(h_.get(), static_cast<std::int32_t>(r)));
    return *this;
  }
  /// The planar branch selection.
  Solver& planar_detection(EopnpPlanarDetection d) {
    detail::check(eopnp_solver_set_planar_detection(h_.get(), static_cast<std::int32_t>(d)));
    return *this;
  }
  /// Maximum damped-Newton iterations per candidate.
  Solver& newton_iterations(std::uint32_t n) {
    detail::check(eopnp_solver_set_newton_iterations(h_.get(), n));
    return *this;
  }
  /// The damped-Newton step tolerance.
  Solver& newton_step_tolerance(double tol) {
    detail::check(eopnp_solver_set_newton_step_tolerance(h_.get(), tol));
    return *this;
  }
  /// Maximum Levenberg-Marquardt iterations.
  Solver& reprojection_iterations(std::uint32_t n) {
    detail::check(eopnp_solver_set_reprojection_iterations(h_.get(), n));
    return *this;
  }
  /// Every generator, every start refined.
  Solver& exhaustive(bool on) {
    detail::check(eopnp_solver_set_exhaustive(h_.get(), on));
    return *this;
  }
  /// The loss of the final refinement and its scale (residual units).
  Solver& loss(EopnpLoss kind, double scale = 0.0) {
    detail::check(eopnp_solver_set_loss(h_.get(), static_cast<std::int32_t>(kind), scale));
    return *this;
  }
  /// The covariance of the solutions (sigma for EOPNP_COVARIANCE_SIGMA).
  Solver& covariance(EopnpCovariance kind, double sigma = 0.0) {
    detail::check(eopnp_solver_set_covariance(h_.get(), static_cast<std::int32_t>(kind), sigma));
    return *this;
  }

  /// The pose of a problem (EOPnP, then the maximum-likelihood refinement).
  Solution solve(const Problem& p) const {
    Solution s;
    detail::check(eopnp_solve(h_.get(), &p.c(), &s));
    return s;
  }
  /// Every local minimum, the best first.
  std::vector<Solution> solve_all(const Problem& p) const {
    std::vector<Solution> all(EOPNP_MAX_SOLUTIONS);
    std::size_t count = 0;
    detail::check(eopnp_solve_all(h_.get(), &p.c(), all.data(), all.size(), &count));
    all.resize(count);
    return all;
  }
  /// Refines a prior pose (x_cam = R X + t) to the maximum-likelihood pose of its basin.
  Solution refine(const Problem& p, const Pose& initial) const {
    Solution s;
    detail::check(eopnp_refine(h_.get(), &p.c(), &initial, &s));
    return s;
  }
  /// Many problems on `threads` threads (0: one per core). Each problem's status is in
  /// `statuses` (resized); throws only for an invalid call, never for a problem's failure.
  std::vector<Solution> solve_batch(const std::vector<Problem>& problems, std::size_t threads,
                                    std::vector<Status>& statuses) const {
    std::vector<EopnpProblem> ps;
    ps.reserve(problems.size());
    for (const Problem& p : problems) ps.push_back(p.c());
    std::vector<Solution> out(problems.size());
    // EOPNP_PANIC marks a status not written: a failure of the call itself (e.g. no threads).
    statuses.assign(problems.size(), EOPNP_PANIC);
    const EopnpStatus st = eopnp_solve_batch(h_.get(), ps.data(), ps.size(), threads, out.data(),
                                             statuses.data());
    if (st != EOPNP_OK && st != EOPNP_PANIC) {
      for (Status s : statuses)
        if (s == EOPNP_PANIC) detail::throw_status(st);
    }
    return out;
  }
  /// The C handle (owned by this object).
  const EopnpSolver* get() const noexcept { return h_.get(); }

 private:
  std::unique_ptr<EopnpSolver, detail::Deleter<EopnpSolver, eopnp_solver_free>> h_;
};

/// The result of Ransac::estimate.
struct RansacResult {
  /// The pose fitted to the inliers.
  Solution solution;
  /// 1 for each correspondence that is an inlier of the pose, 0 otherwise.
  std::vector<std::uint8_t> inliers;
  /// The run's statistics.
  RansacStats stats;
};

/// RANSAC options and robust estimation. The default is the recommended configuration.
class Ransac {
 public:
  Ransac() {
    EopnpRansac* r = nullptr;
    detail::check(eopnp_ransac_create(&r));
    h_.reset(r);
  }
  /// Inlier threshold (pixels, or normalised units for normalised input without focal()).
  Ransac& threshold_px(double px) {
    detail::check(eopnp_ransac_set_threshold_px(h_.get(), px));
    return *this;
  }
  /// Confidence in (0, 1).
  Ransac& confidence(double p) {
    detail::check(eopnp_ransac_set_confidence(h_.get(), p));
    return *this;
  }
  /// The most samples.
  Ransac& max_iterations(std::uint32_t n) {
    detail::check(eopnp_ransac_set_max_iterations(h_.get(), n));
    return *this;
  }
  /// The fewest samples.
  Ransac& min_iterations(std::uint32_t n) {
    detail::check(eopnp_ransac_set_min_iterations(h_.get(), n));
    return *this;
  }
  /// The sampling seed.
  Ransac& seed(std::uint64_t s) {
    detail::check(eopnp_ransac_set_seed(h_.get(), s));
    return *this;
  }
  /// Local optimisation on or off.
  Ransac& local_optimisation(bool on) {
    detail::check(eopnp_ransac_set_local_optimisation(h_.get(), on));
    return *this;
  }
  /// The final threshold as a multiple of the threshold.
  Ransac& final_threshold_factor(double f) {
    detail::check(eopnp_ransac_set_final_threshold_factor(h_.get(), f));
    return *this;
  }
  /// Robust estimation of a problem's pose.
  RansacResult estimate(const Solver& solver, const Problem& p) const {
    RansacResult r{};
    r.inliers.resize(p.size());
    detail::check(eopnp_ransac_estimate(h_.get(), solver.get(), &p.c(), &r.solution,
                                        r.inliers.data(), &r.stats));
    return r;
  }
  /// Many problems on `threads` threads (0: one per core), problem i with the library's seed
  /// problem_seed(seed, i). Each problem's status is in `statuses` (resized); throws only for a
  /// failure of the call itself, never for a problem's.
  std::vector<RansacResult> estimate_batch(const Solver& solver, const std::vector<Problem>& problems,
                                           std::size_t threads, std::vector<Status>& statuses) const {
    std::vector<EopnpProblem> ps;
    std::vector<RansacResult> out(problems.size());
    std::vector<Solution> sols(problems.size());
    std::vector<RansacStats> stats(problems.size());
    std::vector<std::uint8_t*> masks(problems.size());
    ps.reserve(problems.size());
    for (std::size_t i = 0; i < problems.size(); ++i) {
      ps.push_back(problems[i].c());
      out[i].inliers.resize(problems[i].size());
      masks[i] = out[i].inliers.data();
    }
    // EOPNP_PANIC marks a status not written: a failure of the call itself.
    statuses.assign(problems.size(), EOPNP_PANIC);
    const EopnpStatus st = eopnp_ransac_batch(h_.get(), solver.get(), ps.data(), ps.size(), threads,
                                              sols.data(), masks.data(), stats.data(), statuses.data());
    if (st != EOPNP_OK && st != EOPNP_PANIC) {
      for (Status x : statuses)
        if (x == EOPNP_PANIC) detail::throw_status(st);
    }
    for (std::size_t i = 0; i < problems.size(); ++i) {
      out[i].solution = sols[i];
      out[i].stats = stats[i];
    }
    return out;
  }
  /// The C handle (owned by this object).
  const EopnpRansac* get() const noexcept { return h_.get(); }

 private:
  std::unique_ptr<EopnpRansac, detail::Deleter<EopnpRansac, eopnp_ransac_free>> h_;
};

// -------------------------------------------------------------------------------------------
// COLMAP models.

/// A COLMAP reconstruction read from a directory (binary or text).
class Model {
 public:
  /// Reads the model in `dir`.
  static Model read(const std::string& dir) {
    EopnpModel* m = nullptr;
    detail::check(eopnp_model_read(dir.c_str(), &m));
    return Model(m);
  }
  /// The image ids, ascending.
  std::vector<std::uint32_t> image_ids() const {
    std::size_t count = 0;
    const EopnpStatus st = eopnp_model_image_ids(h_.get(), nullptr, 0, &count);
    if (st != EOPNP_OK && st != EOPNP_BUFFER_TOO_SMALL) detail::throw_status(st);
    std::vector<std::uint32_t> ids(count);
    detail::check(eopnp_model_image_ids(h_.get(), ids.data(), ids.size(), &count));
    return ids;
  }
  /// The frame ids (models with rigs), ascending.
  std::vector<std::uint32_t> frame_ids() const {
    std::size_t count = 0;
    const EopnpStatus st = eopnp_model_frame_ids(h_.get(), nullptr, 0, &count);
    if (st != EOPNP_OK && st != EOPNP_BUFFER_TOO_SMALL) detail::throw_status(st);
    std::vector<std::uint32_t> ids(count);
    if (count > 0) detail::check(eopnp_model_frame_ids(h_.get(), ids.data(), ids.size(), &count));
    return ids;
  }
  /// Registers frame `frame_id`: the pose of its rig (with RANSAC when `ransac` is not null).
  FrameRegistration register_frame(std::uint32_t frame_id, const Solver& solver,
                                   const Ransac* ransac = nullptr) const {
    FrameRegistration r{};
    detail::check(eopnp_model_register_frame(h_.get(), frame_id, solver.get(),
                                             ransac ? ransac->get() : nullptr, &r));
    return r;
  }
  /// A copy of camera `camera_id`.
  Camera camera(std::uint32_t camera_id) const {
    EopnpCamera* c = nullptr;
    detail::check(eopnp_model_camera(h_.get(), camera_id, &c));
    return Camera(c);
  }
  /// Registers image `image_id` (with RANSAC when `ransac` is not null), re-estimating with the
  /// pose the intrinsics that `intrinsics` makes free (none by default; FreeIntrinsics).
  Registration register_image(std::uint32_t image_id, const Solver& solver,
                              const Ransac* ransac = nullptr,
                              const FreeIntrinsics& intrinsics = FreeIntrinsics()) const {
    Registration r{};
    detail::check(eopnp_model_register_with(h_.get(), image_id, solver.get(),
                                            ransac ? ransac->get() : nullptr, &intrinsics.c(), &r));
    return r;
  }
  /// Registers the images `image_ids` on `threads` threads (0: one per core), each as
  /// register_image with `intrinsics`. Each image's status is in `statuses` (resized); throws
  /// only for a failure of the call itself.
  std::vector<Registration> register_batch(const std::vector<std::uint32_t>& image_ids,
                                           const Solver& solver, const Ransac* ransac,
                                           std::size_t threads, std::vector<Status>& statuses,
                                           const FreeIntrinsics& intrinsics = FreeIntrinsics()) const {
    std::vector<Registration> out(image_ids.size());
    statuses.assign(image_ids.size(), EOPNP_PANIC);
    const EopnpStatus st = eopnp_model_register_batch_with(
        h_.get(), image_ids.data(), image_ids.size(), solver.get(), ransac ? ransac->get() : nullptr,
        &intrinsics.c(), threads, out.data(), statuses.data());
    if (st != EOPNP_OK && st != EOPNP_PANIC) {
      for (Status x : statuses)
        if (x == EOPNP_PANIC) detail::throw_status(st);
    }
    return out;
  }
  /// The C handle (owned by this object).
  const EopnpModel* get() const noexcept { return h_.get(); }

 private:
  explicit Model(EopnpModel* m) : h_(m) {}
  std::unique_ptr<EopnpModel, detail::Deleter<EopnpModel, eopnp_model_free>> h_;
};

}  // namespace eopnp

// -------------------------------------------------------------------------------------------
// OpenCV-shaped overloads.

#if defined(EOPNP_WITH_OPENCV) || defined(CV_VERSION)
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace eopnp {
namespace cv {

namespace detail {

/// Points as an n x d CV_64F matrix (from vector<Point3f/3d/2f/2d> or an n x d / 1 x n
/// d-channel Mat of float or double), as cv::solvePnP accepts them.
inline ::cv::Mat points(::cv::InputArray a, int d, const char* name) {
  ::cv::Mat m = a.getMat();
  const int n = std::max(m.checkVector(d, CV_32F), m.checkVector(d, CV_64F));
  if (n < 0) {
    EopnpErrorInfo info{};
    info.status = EOPNP_INVALID_ARGUMENT;
    throw InvalidArgumentError(EOPNP_INVALID_ARGUMENT,
                               std::string(name) + ": expected " + std::to_string(d) +
                                   "-vectors of float or double",
                               info);
  }
  ::cv::Mat out;
  m.reshape(1, n).convertTo(out, CV_64F);
  return out.isContinuous() ? out : out.clone();
}

inline Camera camera(::cv::InputArray k_, ::cv::InputArray dist_) {
  ::cv::Mat k;
  k_.getMat().convertTo(k, CV_64F);
  if (k.rows != 3 || k.cols != 3) {
    EopnpErrorInfo info{};
    info.status = EOPNP_INVALID_ARGUMENT;
    throw InvalidArgumentError(EOPNP_INVALID_ARGUMENT, "cameraMatrix must be 3 x 3", info);
  }
  k = k.clone();
  ::cv::Mat d;
  if (!dist_.empty()) {
    dist_.getMat().convertTo(d, CV_64F);
    d = d.reshape(1, 1).clone();
  }
  return Camera::opencv(k.ptr<double>(), d.empty() ? nullptr : d.ptr<double>(),
                        d.empty() ? 0 : static_cast<std::size_t>(d.total()));
}

inline Pose pose_of(::cv::InputArray rvec, ::cv::InputArray tvec) {
  ::cv::Mat r, t, rm;
  rvec.getMat().convertTo(r, CV_64F);
  tvec.getMat().convertTo(t, CV_64F);
  ::cv::Rodrigues(r.reshape(1, 3), rm);
  Pose p{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) p.rotation[3 * i + j] = rm.at<double>(i, j);
    p.translation[i] = t.reshape(1, 3).at<double>(i);
  }
  return p;
}

inline void write_pose(const Solution& s, ::cv::OutputArray rvec, ::cv::OutputArray tvec) {
  ::cv::Mat r(3, 3, CV_64F, const_cast<double*>(s.rotation));
  ::cv::Mat rv;
  ::cv::Rodrigues(r, rv);
  rvec.create(3, 1, CV_64F);
  rv.copyTo(rvec.getMat());
  tvec.create(3, 1, CV_64F);
  ::cv::Mat(3, 1, CV_64F, const_cast<double*>(s.translation)).copyTo(tvec.getMat());
}

}  // namespace detail

/// cv::solvePnP's shape: object points (n 3-vectors), image points (n 2-vectors, pixels in
/// OpenCV's convention), K, distortion (empty, 4, 5, 8, 12 or 14), rvec/tvec out (3 x 1
/// CV_64F). With `useExtrinsicGuess`, rvec/tvec are the prior pose and eopnp refines it
/// (Solver::refine); otherwise EOPnP and the maximum-likelihood refinement (`flags` is ignored:
/// there is one method). Returns true; throws an eopnp::Error on bad input or failure.
inline bool solvePnP(::cv::InputArray objectPoints, ::cv::InputArray imagePoints,
                     ::cv::InputArray cameraMatrix, ::cv::InputArray distCoeffs,
                     ::cv::OutputArray rvec, ::cv::OutputArray tvec,
                     bool useExtrinsicGuess = false, int flags = 0,
                     const Solver& solver = Solver()) {
  (void)flags;
  const ::cv::Mat world = detail::points(objectPoints, 3, "objectPoints");
  const ::cv::Mat image = detail::points(imagePoints, 2, "imagePoints");
  if (world.rows != image.rows)
    eopnp::detail::mismatch("objectPoints and imagePoints have different counts");
  const Camera cam = detail::camera(cameraMatrix, distCoeffs);
  const Problem p = Problem::pixels(world.ptr<double>(), image.ptr<double>(),
                                    static_cast<std::size_t>(world.rows), cam);
  const Solution s = useExtrinsicGuess ? solver.refine(p, detail::pose_of(rvec, tvec))
                                       : solver.solve(p);
  detail::write_pose(s, rvec, tvec);
  return true;
}

/// cv::solvePnPRansac's shape (threshold `reprojectionError` in pixels, `iterationsCount` the
/// most samples, `confidence`; `inliers` out as n_inliers x 1 CV_32S indices). Returns false
/// when RANSAC finds no consensus (as OpenCV does); throws an eopnp::Error on bad input.
/// `useExtrinsicGuess` and `flags` are ignored.
inline bool solvePnPRansac(::cv::InputArray objectPoints, ::cv::InputArray imagePoints,
                           ::cv::InputArray cameraMatrix, ::cv::InputArray distCoeffs,
                           ::cv::OutputArray rvec, ::cv::OutputArray tvec,
                           bool useExtrinsicGuess = false, int iterationsCount = 100,
                           float reprojectionError = 8.0, double confidence = 0.99,
                           ::cv::OutputArray inliers = ::cv::noArray(), int flags = 0) {
  (void)useExtrinsicGuess;
  (void)flags;
  const ::cv::Mat world = detail::points(objectPoints, 3, "objectPoints");
  const ::cv::Mat image = detail::points(imagePoints, 2, "imagePoints");
  if (world.rows != image.rows)
    eopnp::detail::mismatch("objectPoints and imagePoints have different counts");
  const Camera cam = detail::camera(cameraMatrix, distCoeffs);
  const Problem p = Problem::pixels(world.ptr<double>(), image.ptr<double>(),
                                    static_cast<std::size_t>(world.rows), cam);
  Ransac ransac;
  ransac.threshold_px(reprojectionError)
      .confidence(confidence)
      .max_iterations(static_cast<std::uint32_t>(std::max(iterationsCount, 1)));
  RansacResult r;
  try {
    r = ransac.estimate(Solver(), p);
  } catch (const NoConsensusError&) {
    return false;
  }
  detail::write_pose(r.solution, rvec, tvec);
  if (inliers.needed()) {
    std::vector<int> idx;
    for (std::size_t i = 0; i < r.inliers.size(); ++i)
      if (r.inliers[i]) idx.push_back(static_cast<int>(i));
    ::cv::Mat(idx, true).copyTo(inliers);
  }
  return true;
}

}  // namespace cv
}  // namespace eopnp
#endif  // OpenCV

#endif  // EOPNP_HPP
