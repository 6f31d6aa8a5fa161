/*
 * The C interface from C: every function, every kind of bad input (NULL pointers, zero counts,
 * NaNs, mismatched sizes, bad names and enumeration values), the last error per thread with
 * several threads solving at once, and the poses equal to the Rust library's bit for bit (the
 * reference file written by `cargo run -p eopnp-capi --example reference_poses -- FILE`).
 *
 * Usage: test_capi REFERENCE_FILE COLMAP_MODEL_DIR COLMAP_RIG_MODEL_DIR
 */
#include "eopnp.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;
static int checks = 0;

#define CHECK(cond)                                                              \
  do {                                                                           \
    ++checks;                                                                    \
    if (!(cond)) {                                                               \
      ++failures;                                                                \
      fprintf(stderr, "%s:%d: CHECK failed: %s (last error: %s)\n", __FILE__,    \
              __LINE__, #cond, eopnp_last_error_message());                      \
    }                                                                            \
  } while (0)

/* `call` returns `status`, and the thread's last error then has that status and a message. */
#define EXPECT(want_, call)                                                          \
  do {                                                                                \
    EopnpStatus got_ = (call);                                                        \
    ++checks;                                                                         \
    if (got_ != (want_)) {                                                           \
      ++failures;                                                                     \
      fprintf(stderr, "%s:%d: %s returned %s, expected %s (last error: %s)\n",        \
              __FILE__, __LINE__, #call, eopnp_status_name(got_),                     \
              eopnp_status_name(want_), eopnp_last_error_message());                 \
    } else if ((want_) != EOPNP_OK) {                                                \
      EopnpErrorInfo info_;                                                           \
      CHECK(eopnp_last_error(&info_) == EOPNP_OK);                                    \
      CHECK(info_.status == (want_));                                                \
      CHECK(strlen(eopnp_last_error_message()) > 0);                                  \
    }                                                                                 \
  } while (0)

/* ---------------------------------------------------------------------------------------- */
/* The reference file.                                                                       */

typedef struct {
  int kind;
  size_t n;
  double *world, *image, *weights;
  double prior[12];
  double rotation[9], translation[3], cost, covariance[36];
  uint8_t *mask;
} Case;

static double from_bits(unsigned long long b) {
  double d;
  memcpy(&d, &b, sizeof d);
  return d;
}

static int read_doubles(FILE *f, const char *name, double *out, size_t count) {
  char word[32];
  if (fscanf(f, "%31s", word) != 1 || strcmp(word, name) != 0) return 0;
  for (size_t i = 0; i < count; ++i) {
    unsigned long long b;
    if (fscanf(f, "%llx", &b) != 1) return 0;
    out[i] = from_bits(b);
  }
  return 1;
}

static int read_case(FILE *f, Case *c) {
  char word[32];
  if (fscanf(f, "%31s", word) != 1) return 0;
  if (strcmp(word, "case") != 0 || fscanf(f, "%d %zu", &c->kind, &c->n) != 2) return -1;
  size_t n = c->n;
  c->world = malloc(3 * n * sizeof(double));
  c->image = malloc(2 * n * sizeof(double));
  c->weights = malloc(n * sizeof(double));
  c->mask = malloc(n);
  if (!read_doubles(f, "world", c->world, 3 * n) || !read_doubles(f, "image", c->image, 2 * n) ||
      !read_doubles(f, "weights", c->weights, n) || !read_doubles(f, "prior", c->prior, 12) ||
      !read_doubles(f, "rotation", c->rotation, 9) ||
      !read_doubles(f, "translation", c->translation, 3) ||
      !read_doubles(f, "cost", &c->cost, 1) || !read_doubles(f, "covariance", c->covariance, 36))
    return -1;
  if (fscanf(f, "%31s", word) != 1 || strcmp(word, "mask") != 0) return -1;
  for (size_t i = 0; i < n; ++i) {
    int m;
    if (fscanf(f, "%d", &m) != 1) return -1;
    c->mask[i] = (uint8_t)m;
  }
  return 1;
}

static void free_case(Case *c) {
  free(c->world);
  free(c->image);
  free(c->weights);
  free(c->mask);
}

static const double COLMAP_PARAMS[8] = {800.0, 810.0, 320.0, 240.0, -0.05, 0.01, 1e-3, -5e-4};
static const double K[9] = {800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0};
static const double DIST[5] = {-0.1, 0.02, 1e-3, -5e-4, 0.001};

/* Solves one reference case through the C interface; 1 if every double matches bit for bit. */
static int solve_case(const Case *c) {
  EopnpSolver *solver = NULL;
  EopnpRansac *ransac = NULL;
  EopnpCamera *cam = NULL;
  EopnpSolution s;
  int ok = 1;
  double *ws = NULL, *is = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&solver));
  EopnpProblem p = {0};
  p.n = c->n;
  p.world = c->world;
  p.image = c->image;
  uint8_t *mask = malloc(c->n);
  memset(mask, 1, c->n);
  if (c->kind == 1 || c->kind == 2)
    EXPECT(EOPNP_OK, eopnp_camera_from_colmap("OPENCV", 640, 480, COLMAP_PARAMS, 8, &cam));
  if (c->kind == 6) {
    EXPECT(EOPNP_OK, eopnp_camera_from_opencv(K, DIST, 5, &cam));
    /* Strided copies: world points 4 doubles apart, image points 3 apart. */
    ws = malloc(4 * c->n * sizeof(double));
    is = malloc(3 * c->n * sizeof(double));
    for (size_t i = 0; i < c->n; ++i) {
      memcpy(ws + 4 * i, c->world + 3 * i, 3 * sizeof(double));
      ws[4 * i + 3] = NAN;
      memcpy(is + 3 * i, c->image + 2 * i, 2 * sizeof(double));
      is[3 * i + 2] = NAN;
    }
    p.world = ws;
    p.world_stride = 4;
    p.image = is;
    p.image_stride = 3;
  }
  p.camera = cam;
  EopnpStatus st = EOPNP_OK;
  switch (c->kind) {
    case 2:
      p.weights = c->weights;
      EXPECT(EOPNP_OK, eopnp_solver_set_loss(solver, EOPNP_LOSS_HUBER, 2.0));
      EXPECT(EOPNP_OK, eopnp_solver_set_covariance(solver, EOPNP_COVARIANCE_SIGMA, 1.0));
      st = eopnp_solve(solver, &p, &s);
      break;
    case 3:
      EXPECT(EOPNP_OK, eopnp_solver_set_refinement(solver, EOPNP_REFINEMENT_ALGEBRAIC));
      st = eopnp_solve(solver, &p, &s);
      break;
    case 4: {
      EopnpPose prior;
      memcpy(prior.rotation, c->prior, sizeof prior.rotation);
      memcpy(prior.translation, c->prior + 9, sizeof prior.translation);
      st = eopnp_refine(solver, &p, &prior, &s);
      break;
    }
    case 5: {
      EopnpRansacStats stats;
      p.focal_x = 800.0;
      p.focal_y = 800.0;
      EXPECT(EOPNP_OK, eopnp_ransac_create(&ransac));
      EXPECT(EOPNP_OK, eopnp_ransac_set_threshold_px(ransac, 2.0));
      EXPECT(EOPNP_OK, eopnp_ransac_set_seed(ransac, 9));
      st = eopnp_ransac_estimate(ransac, solver, &p, &s, mask, &stats);
      CHECK(st != EOPNP_OK || stats.inliers > 0);
      break;
    }
    default:
      st = eopnp_solve(solver, &p, &s);
  }
  CHECK(st == EOPNP_OK);
  if (st == EOPNP_OK) {
    ok = memcmp(s.rotation, c->rotation, sizeof s.rotation) == 0 &&
         memcmp(s.translation, c->translation, sizeof s.translation) == 0 &&
         memcmp(&s.cost, &c->cost, sizeof s.cost) == 0 &&
         memcmp(s.covariance, c->covariance, sizeof s.covariance) == 0 &&
         memcmp(mask, c->mask, c->n) == 0 && s.has_covariance == (c->kind == 2);
  } else {
    ok = 0;
  }
  free(mask);
  free(ws);
  free(is);
  eopnp_camera_free(cam);
  eopnp_ransac_free(ransac);
  eopnp_solver_free(solver);
  return ok;
}

static void test_reference(const char *path) {
  FILE *f = fopen(path, "r");
  CHECK(f != NULL);
  if (!f) return;
  int cases = 0, equal = 0;
  for (;;) {
    Case c = {0};
    int r = read_case(f, &c);
    if (r == 0) break;
    CHECK(r == 1);
    if (r != 1) {
      free_case(&c);
      break;
    }
    ++cases;
    int ok = solve_case(&c);
    CHECK(ok);
    if (!ok) fprintf(stderr, "reference case %d (kind %d, n %zu) differs\n", cases, c.kind, c.n);
    equal += ok;
    free_case(&c);
  }
  fclose(f);
  CHECK(cases == 21);
  printf("reference: %d of %d cases equal to the Rust library's bit for bit\n", equal, cases);
}

/* ---------------------------------------------------------------------------------------- */
/* A synthetic problem (the same camera as the reference's case 1).                         */

#define N 12
static double W[3 * N], M[2 * N], PX[2 * N];

static void make_problem(void) {
  for (int i = 0; i < N; ++i) {
    double x = -1.0 + 0.37 * (i % 6), y = -0.8 + 0.5 * ((3 * i) % 4), z = 0.3 * ((2 * i) % 5) - 0.6;
    W[3 * i] = x;
    W[3 * i + 1] = y;
    W[3 * i + 2] = z;
    /* Camera: R = I, t = (0.1, -0.2, 6). */
    double cx = x + 0.1, cy = y - 0.2, cz = z + 6.0;
    M[2 * i] = cx / cz;
    M[2 * i + 1] = cy / cz;
    PX[2 * i] = 800.0 * cx / cz + 320.0;
    PX[2 * i + 1] = 800.0 * cy / cz + 240.0;
  }
}

static EopnpProblem normalised(size_t n) {
  EopnpProblem p = {0};
  p.n = n;
  p.world = W;
  p.image = M;
  return p;
}

static void test_errors_and_version(void) {
  CHECK(strcmp(eopnp_version(), "0.1.0") == 0);
  CHECK(strcmp(eopnp_status_name(EOPNP_OK), "EOPNP_OK") == 0);
  CHECK(strcmp(eopnp_status_name(EOPNP_NO_CONSENSUS), "EOPNP_NO_CONSENSUS") == 0);
  CHECK(strcmp(eopnp_status_name(-1), "EOPNP_UNKNOWN_STATUS") == 0);
  CHECK(strcmp(eopnp_status_name(1000), "EOPNP_UNKNOWN_STATUS") == 0);
  EXPECT(EOPNP_NULL_POINTER, eopnp_last_error(NULL));
  CHECK(strcmp(eopnp_last_error_message(), "`out` is NULL") == 0);
}

static void test_solver_options(void) {
  EopnpSolver *s = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_create(NULL));
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EXPECT(EOPNP_OK, eopnp_solver_set_refinement(s, EOPNP_REFINEMENT_ALGEBRAIC));
  EXPECT(EOPNP_OK, eopnp_solver_set_refinement(s, EOPNP_REFINEMENT_REPROJECTION));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_refinement(s, 7));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_refinement(NULL, 0));
  EXPECT(EOPNP_OK, eopnp_solver_set_planar_detection(s, EOPNP_PLANAR_NON_PLANAR));
  EXPECT(EOPNP_OK, eopnp_solver_set_planar_detection(s, EOPNP_PLANAR_AUTO));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_planar_detection(s, -1));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_planar_detection(NULL, 0));
  EXPECT(EOPNP_OK, eopnp_solver_set_newton_iterations(s, 60));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_newton_iterations(NULL, 60));
  EXPECT(EOPNP_OK, eopnp_solver_set_newton_step_tolerance(s, 1e-12));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_newton_step_tolerance(s, NAN));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_newton_step_tolerance(s, -1.0));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_newton_step_tolerance(NULL, 1e-12));
  EXPECT(EOPNP_OK, eopnp_solver_set_reprojection_iterations(s, 100));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_reprojection_iterations(NULL, 100));
  EXPECT(EOPNP_OK, eopnp_solver_set_exhaustive(s, true));
  EXPECT(EOPNP_OK, eopnp_solver_set_exhaustive(s, false));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_exhaustive(NULL, true));
  EXPECT(EOPNP_OK, eopnp_solver_set_loss(s, EOPNP_LOSS_CAUCHY, 1e-3));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solver_set_loss(s, EOPNP_LOSS_HUBER, NAN));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solver_set_loss(s, EOPNP_LOSS_HUBER, 0.0));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solver_set_loss(s, EOPNP_LOSS_HUBER, 1e-200));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_loss(s, 3, 1.0));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_loss(NULL, 0, 1.0));
  EXPECT(EOPNP_OK, eopnp_solver_set_loss(s, EOPNP_LOSS_SQUARED, NAN)); /* scale ignored */
  EXPECT(EOPNP_OK, eopnp_solver_set_covariance(s, EOPNP_COVARIANCE_ESTIMATED, 0.0));
  EXPECT(EOPNP_OK, eopnp_solver_set_covariance(s, EOPNP_COVARIANCE_SIGMA, 1e-3));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solver_set_covariance(s, EOPNP_COVARIANCE_SIGMA, NAN));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solver_set_covariance(s, EOPNP_COVARIANCE_SIGMA, -1.0));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solver_set_covariance(s, 9, 1.0));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solver_set_covariance(NULL, 0, 1.0));
  /* The covariance reaches the solution. */
  EopnpProblem p = normalised(N);
  EopnpSolution out;
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &out));
  CHECK(out.has_covariance && out.covariance[35] > 0.0 && out.covariance_sigma == 1e-3);
  eopnp_solver_free(s);
  eopnp_solver_free(NULL);
}

static void test_ransac_options(void) {
  EopnpRansac *r = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_create(NULL));
  EXPECT(EOPNP_OK, eopnp_ransac_create(&r));
  EXPECT(EOPNP_OK, eopnp_ransac_set_threshold_px(r, 3.0));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_set_threshold_px(r, NAN));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_threshold_px(NULL, 3.0));
  EXPECT(EOPNP_OK, eopnp_ransac_set_confidence(r, 0.99));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_set_confidence(r, INFINITY));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_confidence(NULL, 0.99));
  EXPECT(EOPNP_OK, eopnp_ransac_set_max_iterations(r, 500));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_max_iterations(NULL, 500));
  EXPECT(EOPNP_OK, eopnp_ransac_set_min_iterations(r, 10));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_min_iterations(NULL, 10));
  EXPECT(EOPNP_OK, eopnp_ransac_set_seed(r, 3));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_seed(NULL, 3));
  EXPECT(EOPNP_OK, eopnp_ransac_set_local_optimisation(r, false));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_local_optimisation(NULL, true));
  EXPECT(EOPNP_OK, eopnp_ransac_set_final_threshold_factor(r, 1.5));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_set_final_threshold_factor(r, NAN));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_set_final_threshold_factor(NULL, 1.5));
  /* Out of range but finite: the library's check at estimation. */
  EopnpSolver *s = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EopnpProblem p = normalised(N);
  EopnpSolution out;
  EXPECT(EOPNP_OK, eopnp_ransac_set_confidence(r, 1.5));
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_estimate(r, s, &p, &out, NULL, NULL));
  CHECK(strstr(eopnp_last_error_message(), "confidence") != NULL);
  eopnp_solver_free(s);
  eopnp_ransac_free(r);
  eopnp_ransac_free(NULL);
}

static void test_cameras(void) {
  EopnpCamera *c = NULL;
  double params[4] = {800.0, 320.0, 240.0, 0.01};
  EXPECT(EOPNP_OK, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, params, 4, &c));
  double m[2] = {0.1, -0.05}, px[2], back[2];
  EXPECT(EOPNP_OK, eopnp_camera_project(c, m, px));
  EXPECT(EOPNP_OK, eopnp_camera_undistort(c, px, back));
  CHECK(fabs(back[0] - m[0]) < 1e-12 && fabs(back[1] - m[1]) < 1e-12);
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_project(NULL, m, px));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_project(c, NULL, px));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_project(c, m, NULL));
  double nan2[2] = {NAN, 0.0};
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_project(c, nan2, px));
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_undistort(c, nan2, back));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_undistort(NULL, px, back));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_undistort(c, NULL, back));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_undistort(c, px, NULL));
  /* The description and the parameters; a buffer too small; the count alone; NULLs. */
  EopnpCameraInfo info;
  EXPECT(EOPNP_OK, eopnp_camera_info(c, &info));
  CHECK(strcmp(info.model, "SIMPLE_RADIAL") == 0);
  CHECK(info.width == 640 && info.height == 480 && info.n_params == 4);
  CHECK(info.fx == 800.0 && info.fy == 800.0);
  double got[4] = {0.0, 0.0, 0.0, 0.0};
  size_t count = 0;
  EXPECT(EOPNP_OK, eopnp_camera_params(c, got, 4, &count));
  CHECK(count == 4 && memcmp(got, params, sizeof got) == 0);
  double two[2] = {0.0, 0.0};
  count = 0;
  EXPECT(EOPNP_BUFFER_TOO_SMALL, eopnp_camera_params(c, two, 2, &count));
  CHECK(count == 4 && two[0] == 800.0 && two[1] == 320.0);
  count = 0;
  EXPECT(EOPNP_BUFFER_TOO_SMALL, eopnp_camera_params(c, NULL, 0, &count));
  CHECK(count == 4);
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_params(c, NULL, 4, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_params(c, got, 4, NULL));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_params(NULL, got, 4, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_info(NULL, &info));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_info(c, NULL));
  eopnp_camera_free(c);
  c = NULL;
  /* Bad model name, wrong parameter count, NaN parameter, NULLs. */
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_colmap("NO_SUCH_MODEL", 640, 480, params, 4, &c));
  CHECK(strstr(eopnp_last_error_message(), "NO_SUCH_MODEL") != NULL);
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, params, 3, &c));
  CHECK(strstr(eopnp_last_error_message(), "takes 4 parameters") != NULL);
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, params, 0, &c));
  params[0] = NAN;
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, params, 4, &c));
  params[0] = -800.0;
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, params, 4, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_colmap(NULL, 640, 480, params, 4, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_colmap("PINHOLE", 640, 480, NULL, 4, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_colmap("PINHOLE", 640, 480, params, 4, NULL));
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_camera_from_colmap("\xff\xfe", 640, 480, params, 4, &c));
  CHECK(c == NULL);
  /* OpenCV: K and 0, 4, 5, 8 coefficients; a bad count; a skewed K. */
  double dist[8] = {-0.1, 0.01, 1e-3, 1e-3, 0.0, 0.0, 0.0, 0.0};
  EXPECT(EOPNP_OK, eopnp_camera_from_opencv(K, NULL, 0, &c));
  eopnp_camera_free(c);
  EXPECT(EOPNP_OK, eopnp_camera_from_opencv(K, dist, 4, &c));
  eopnp_camera_free(c);
  EXPECT(EOPNP_OK, eopnp_camera_from_opencv(K, dist, 8, &c));
  /* An OpenCV camera is described by its COLMAP model: K's intrinsics, then the coefficients. */
  EXPECT(EOPNP_OK, eopnp_camera_info(c, &info));
  CHECK(strcmp(info.model, "FULL_OPENCV") == 0 && info.n_params == 12);
  CHECK(info.width == 0 && info.height == 0 && info.fx == K[0] && info.fy == K[4]);
  double full[12];
  EXPECT(EOPNP_OK, eopnp_camera_params(c, full, 12, &count));
  CHECK(full[2] == K[2] && full[3] == K[5] && full[4] == dist[0] && full[11] == dist[7]);
  eopnp_camera_free(c);
  c = NULL;
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_opencv(K, dist, 3, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv(K, NULL, 4, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv(NULL, dist, 4, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv(K, dist, 4, NULL));
  double skew[9] = {800.0, 1.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0};
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_opencv(skew, dist, 4, &c));
  double knan[9] = {NAN, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0};
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_from_opencv(knan, NULL, 0, &c));
  EXPECT(EOPNP_OK, eopnp_camera_from_opencv_fisheye(K, dist, &c));
  eopnp_camera_free(c);
  c = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv_fisheye(K, NULL, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv_fisheye(NULL, dist, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_from_opencv_fisheye(K, dist, NULL));
  EXPECT(EOPNP_OK, eopnp_camera_pinhole(800.0, 800.0, 320.0, 240.0, &c));
  eopnp_camera_free(c);
  c = NULL;
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_pinhole(0.0, 800.0, 320.0, 240.0, &c));
  EXPECT(EOPNP_CAMERA_ERROR, eopnp_camera_pinhole(800.0, NAN, 320.0, 240.0, &c));
  EXPECT(EOPNP_NULL_POINTER, eopnp_camera_pinhole(800.0, 800.0, 320.0, 240.0, NULL));
  CHECK(c == NULL);
  eopnp_camera_free(NULL);
}

static void test_solves(void) {
  EopnpSolver *s = NULL;
  EopnpCamera *cam = NULL;
  EopnpSolution out, all[EOPNP_MAX_SOLUTIONS];
  size_t count = 0;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EXPECT(EOPNP_OK, eopnp_camera_pinhole(800.0, 800.0, 320.0, 240.0, &cam));

  /* Normalised and pixel input: the true pose. */
  EopnpProblem p = normalised(N);
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &out));
  CHECK(fabs(out.translation[2] - 6.0) < 1e-9 && fabs(out.rotation[0] - 1.0) < 1e-9);
  CHECK(out.used == N && out.skipped == 0 && out.cheirality_ok && out.converged);
  EopnpProblem px = p;
  px.image = PX;
  px.camera = cam;
  EXPECT(EOPNP_OK, eopnp_solve(s, &px, &out));
  CHECK(fabs(out.translation[0] - 0.1) < 1e-9 && fabs(out.translation[1] + 0.2) < 1e-9);

  /* Bad input: NULLs, zero and too few points, NaN in each input, negative weight, strides,
   * degenerate points, camera and rig together, rig cameras without a rig. */
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(NULL, &p, &out));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(s, NULL, &out));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(s, &p, NULL));
  EopnpProblem q = p;
  q.world = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(s, &q, &out));
  q = p;
  q.image = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(s, &q, &out));
  q = normalised(0);
  EXPECT(EOPNP_TOO_FEW_POINTS, eopnp_solve(s, &q, &out));
  EopnpErrorInfo info;
  CHECK(eopnp_last_error(&info) == EOPNP_OK && info.got == 0 && info.need == 4);
  q = normalised(3);
  EXPECT(EOPNP_TOO_FEW_POINTS, eopnp_solve(s, &q, &out));
  double w2[3 * N], m2[2 * N], wt[N];
  memcpy(w2, W, sizeof W);
  memcpy(m2, M, sizeof M);
  for (int i = 0; i < N; ++i) wt[i] = 1.0;
  q = normalised(N);
  q.world = w2;
  w2[3 * 5 + 2] = NAN;
  EXPECT(EOPNP_NON_FINITE, eopnp_solve(s, &q, &out));
  CHECK(eopnp_last_error(&info) == EOPNP_OK && info.index == 5 && info.input == EOPNP_INPUT_WORLD);
  w2[3 * 5 + 2] = W[3 * 5 + 2];
  q.image = m2;
  m2[2 * 7] = INFINITY;
  EXPECT(EOPNP_NON_FINITE, eopnp_solve(s, &q, &out));
  CHECK(eopnp_last_error(&info) == EOPNP_OK && info.index == 7 && info.input == EOPNP_INPUT_IMAGE);
  m2[2 * 7] = M[2 * 7];
  q.weights = wt;
  wt[2] = NAN;
  EXPECT(EOPNP_NON_FINITE, eopnp_solve(s, &q, &out));
  CHECK(eopnp_last_error(&info) == EOPNP_OK && info.input == EOPNP_INPUT_WEIGHT);
  wt[2] = -1.0;
  EXPECT(EOPNP_INVALID_WEIGHT, eopnp_solve(s, &q, &out));
  wt[2] = 1.0;
  EXPECT(EOPNP_OK, eopnp_solve(s, &q, &out));
  q.world_stride = 2;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  q.world_stride = 0;
  q.image_stride = 1;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  q.image_stride = 0;
  q.n = SIZE_MAX / 4;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  q.n = N;
  q.world = (const double *)((const char *)W + 1);
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  q.world = W;
  /* All world points on a line. */
  double line[3 * N];
  for (int i = 0; i < N; ++i) {
    line[3 * i] = i;
    line[3 * i + 1] = 2.0 * i;
    line[3 * i + 2] = 1.0;
  }
  q.world = line;
  EXPECT(EOPNP_DEGENERATE, eopnp_solve(s, &q, &out));
  CHECK(eopnp_last_error(&info) == EOPNP_OK &&
        info.degenerate == EOPNP_DEGENERATE_COLLINEAR_WORLD_POINTS);
  q.world = W;
  EopnpRig *rig = NULL;
  const EopnpCamera *cams[1] = {cam};
  EopnpPose identity = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}};
  EXPECT(EOPNP_OK, eopnp_rig_create(cams, &identity, 1, &rig));
  q.camera = cam;
  q.rig = rig;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  uint32_t which[N] = {0};
  q.camera = NULL;
  q.rig = NULL;
  q.rig_cameras = which;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &q, &out));
  /* A rig of one camera: the pinhole problem's pose. */
  q = px;
  q.camera = NULL;
  q.rig = rig;
  q.rig_cameras = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve(s, &q, &out));
  q.rig_cameras = which;
  EXPECT(EOPNP_OK, eopnp_solve(s, &q, &out));
  CHECK(fabs(out.translation[2] - 6.0) < 1e-9);
  which[3] = 1;
  EXPECT(EOPNP_UNKNOWN_CAMERA, eopnp_solve(s, &q, &out));
  which[3] = 0;
  /* Rig errors: no camera, NULLs, a non-rotation, a NaN pose. */
  EopnpRig *bad = NULL;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_rig_create(cams, &identity, 0, &bad));
  EXPECT(EOPNP_NULL_POINTER, eopnp_rig_create(NULL, &identity, 1, &bad));
  EXPECT(EOPNP_NULL_POINTER, eopnp_rig_create(cams, NULL, 1, &bad));
  EXPECT(EOPNP_NULL_POINTER, eopnp_rig_create(cams, &identity, 1, NULL));
  const EopnpCamera *nocam[1] = {NULL};
  EXPECT(EOPNP_NULL_POINTER, eopnp_rig_create(nocam, &identity, 1, &bad));
  EopnpPose scaled = {{2, 0, 0, 0, 2, 0, 0, 0, 2}, {0, 0, 0}};
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_rig_create(cams, &scaled, 1, &bad));
  EopnpPose nanpose = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {NAN, 0, 0}};
  EXPECT(EOPNP_INVALID_OPTION, eopnp_rig_create(cams, &nanpose, 1, &bad));
  CHECK(bad == NULL);
  eopnp_rig_free(rig);
  eopnp_rig_free(NULL);

  /* Every minimum; a buffer too small; NULLs. */
  q = normalised(4);
  EXPECT(EOPNP_OK, eopnp_solve_all(s, &q, all, EOPNP_MAX_SOLUTIONS, &count));
  CHECK(count >= 1 && count <= EOPNP_MAX_SOLUTIONS);
  size_t need = 0;
  EXPECT(count > 0 ? EOPNP_BUFFER_TOO_SMALL : EOPNP_OK, eopnp_solve_all(s, &q, NULL, 0, &need));
  CHECK(need == count);
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_all(s, &q, NULL, 2, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_all(s, &q, all, 2, NULL));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_all(NULL, &q, all, 2, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_all(s, NULL, all, 2, &count));

  /* Refinement from a prior pose; a NaN prior, a reflection, NULLs. */
  EopnpPose prior = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0.15, -0.25, 5.8}};
  p = normalised(N);
  EXPECT(EOPNP_OK, eopnp_refine(s, &p, &prior, &out));
  CHECK(fabs(out.translation[2] - 6.0) < 1e-9 && out.source == EOPNP_SOURCE_INITIAL);
  prior.translation[0] = NAN;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_refine(s, &p, &prior, &out));
  prior.translation[0] = 0.0;
  prior.rotation[8] = -1.0;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_refine(s, &p, &prior, &out));
  prior.rotation[8] = NAN;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_refine(s, &p, &prior, &out));
  prior.rotation[8] = 1.0;
  EXPECT(EOPNP_NULL_POINTER, eopnp_refine(s, &p, NULL, &out));
  EXPECT(EOPNP_NULL_POINTER, eopnp_refine(NULL, &p, &prior, &out));
  EXPECT(EOPNP_NULL_POINTER, eopnp_refine(s, NULL, &prior, &out));
  EXPECT(EOPNP_NULL_POINTER, eopnp_refine(s, &p, &prior, NULL));

  /* RANSAC: mask and statistics; no consensus; NULLs. */
  EopnpRansac *r = NULL;
  EopnpRansacStats stats;
  uint8_t mask[N];
  EXPECT(EOPNP_OK, eopnp_ransac_create(&r));
  px = normalised(N);
  px.image = PX;
  px.camera = cam;
  EXPECT(EOPNP_OK, eopnp_ransac_estimate(r, s, &px, &out, mask, &stats));
  CHECK(stats.inliers == N && stats.iterations >= 1);
  for (int i = 0; i < N; ++i) CHECK(mask[i] == 1);
  EXPECT(EOPNP_OK, eopnp_ransac_estimate(r, s, &px, &out, NULL, NULL));
  double scrambled[2 * N];
  for (int i = 0; i < N; ++i) {
    scrambled[2 * i] = PX[2 * ((i * 5) % N)];
    scrambled[2 * i + 1] = PX[2 * ((i * 7 + 3) % N) + 1];
  }
  q = px;
  q.image = scrambled;
  EXPECT(EOPNP_NO_CONSENSUS, eopnp_ransac_estimate(r, s, &q, &out, mask, &stats));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_estimate(NULL, s, &px, &out, mask, &stats));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_estimate(r, NULL, &px, &out, mask, &stats));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_estimate(r, s, NULL, &out, mask, &stats));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_estimate(r, s, &px, NULL, mask, &stats));
  q = normalised(N);
  q.focal_x = -1.0;
  q.focal_y = 800.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_estimate(r, s, &q, &out, NULL, NULL));

  /* Batches: statuses per problem; the first failure reported with its index. */
  EopnpProblem batch[4] = {normalised(N), px, normalised(2), normalised(N)};
  EopnpSolution outs[4];
  EopnpStatus statuses[4];
  EXPECT(EOPNP_TOO_FEW_POINTS, eopnp_solve_batch(s, batch, 4, 2, outs, statuses));
  CHECK(eopnp_last_error(&info) == EOPNP_OK && info.index == 2);
  CHECK(strncmp(eopnp_last_error_message(), "problem 2: ", 11) == 0);
  CHECK(statuses[0] == EOPNP_OK && statuses[1] == EOPNP_OK &&
        statuses[2] == EOPNP_TOO_FEW_POINTS && statuses[3] == EOPNP_OK);
  CHECK(memcmp(&outs[0].translation, &outs[3].translation, sizeof outs[0].translation) == 0);
  batch[2] = normalised(N);
  batch[2].world = NULL;
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_batch(s, batch, 4, 0, outs, statuses));
  CHECK(statuses[2] == EOPNP_NULL_POINTER && statuses[3] == EOPNP_OK);
  batch[2] = normalised(N);
  EXPECT(EOPNP_OK, eopnp_solve_batch(s, batch, 4, 1, outs, statuses));
  EXPECT(EOPNP_OK, eopnp_solve_batch(s, batch, 0, 1, outs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_batch(NULL, batch, 4, 1, outs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_batch(s, NULL, 4, 1, outs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_batch(s, batch, 4, 1, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_solve_batch(s, batch, 4, 1, outs, NULL));
  uint8_t m0[N], m1[N];
  uint8_t *masks[4] = {m0, m1, NULL, NULL};
  EopnpRansacStats bstats[4];
  batch[0] = px;
  batch[1] = px;
  batch[2] = px;
  batch[3] = q; /* focal -1: invalid option */
  EXPECT(EOPNP_INVALID_OPTION, eopnp_ransac_batch(r, s, batch, 4, 2, outs, masks, bstats, statuses));
  CHECK(statuses[0] == EOPNP_OK && statuses[1] == EOPNP_OK && statuses[2] == EOPNP_OK &&
        statuses[3] == EOPNP_INVALID_OPTION);
  CHECK(bstats[0].inliers == N && m0[0] == 1 && m1[N - 1] == 1);
  EXPECT(EOPNP_OK, eopnp_ransac_batch(r, s, batch, 3, 2, outs, NULL, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_batch(NULL, s, batch, 3, 2, outs, NULL, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_batch(r, NULL, batch, 3, 2, outs, NULL, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_batch(r, s, NULL, 3, 2, outs, NULL, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_batch(r, s, batch, 3, 2, NULL, NULL, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_ransac_batch(r, s, batch, 3, 2, outs, NULL, NULL, NULL));
  eopnp_ransac_free(r);
  eopnp_camera_free(cam);
  eopnp_solver_free(s);
}

static void test_model(const char *dir) {
  EopnpModel *model = NULL;
  EXPECT(EOPNP_OK, eopnp_model_read(dir, &model));
  size_t count = 0;
  EXPECT(EOPNP_BUFFER_TOO_SMALL, eopnp_model_image_ids(model, NULL, 0, &count));
  CHECK(count == 6);
  uint32_t ids[6];
  EXPECT(EOPNP_OK, eopnp_model_image_ids(model, ids, 6, &count));
  CHECK(ids[0] < ids[5]);
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_image_ids(model, ids, 6, NULL));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_image_ids(model, NULL, 6, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_image_ids(NULL, ids, 6, &count));
  EopnpCamera *cam = NULL;
  EXPECT(EOPNP_OK, eopnp_model_camera(model, 1, &cam));
  eopnp_camera_free(cam);
  EXPECT(EOPNP_REGISTER_ERROR, eopnp_model_camera(model, 999, &cam));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_camera(model, 1, NULL));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_camera(NULL, 1, &cam));

  EopnpSolver *s = NULL;
  EopnpRansac *r = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EXPECT(EOPNP_OK, eopnp_ransac_create(&r));
  EopnpRegistration reg;
  EXPECT(EOPNP_OK, eopnp_model_register(model, ids[0], s, NULL, &reg));
  CHECK(reg.image_id == ids[0] && !reg.has_ransac && reg.n >= 4 && reg.rotation_error_deg < 1.0);
  EXPECT(EOPNP_OK, eopnp_model_register(model, ids[1], s, r, &reg));
  CHECK(reg.has_ransac && reg.ransac.iterations >= 1 && reg.inliers > 0);
  EXPECT(EOPNP_REGISTER_ERROR, eopnp_model_register(model, 12345, s, NULL, &reg));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register(NULL, ids[0], s, NULL, &reg));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register(model, ids[0], NULL, NULL, &reg));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register(model, ids[0], s, NULL, NULL));
  EopnpRegistration regs[7];
  EopnpStatus statuses[7];
  uint32_t with_bad[7];
  memcpy(with_bad, ids, sizeof ids);
  with_bad[6] = 12345;
  EXPECT(EOPNP_REGISTER_ERROR,
         eopnp_model_register_batch(model, with_bad, 7, s, r, 2, regs, statuses));
  for (int i = 0; i < 6; ++i) CHECK(statuses[i] == EOPNP_OK && regs[i].image_id == ids[i]);
  CHECK(statuses[6] == EOPNP_REGISTER_ERROR);
  EXPECT(EOPNP_OK, eopnp_model_register_batch(model, ids, 6, s, NULL, 1, regs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_batch(NULL, ids, 6, s, NULL, 1, regs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_batch(model, NULL, 6, s, NULL, 1, regs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_batch(model, ids, 6, NULL, NULL, 1, regs, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_batch(model, ids, 6, s, NULL, 1, NULL, statuses));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_batch(model, ids, 6, s, NULL, 1, regs, NULL));

  /* Free intrinsics: the focal length re-estimated from the model camera's own (image 1 sees
   * camera 3, images.txt). */
  EopnpFreeIntrinsics fi = {0};
  fi.unknown_focal = true;
  CHECK(ids[0] == 1);
  memset(&reg, 0xff, sizeof reg);
  EXPECT(EOPNP_OK, eopnp_model_register_with(model, ids[0], s, NULL, &fi, &reg));
  CHECK(reg.image_id == ids[0] && !reg.has_ransac && reg.rotation_error_deg < 0.01);
  CHECK(reg.has_focal_error && reg.focal_error_pct >= 0.0 && reg.focal_error_pct < 0.01);
  CHECK(reg.solution.focal_estimated && reg.solution.camera_estimated);
  CHECK(reg.solution.camera_n_params == 4 && reg.solution.camera_params[0] == reg.solution.focal_x);
  {
    EopnpCamera *c3 = NULL;
    EopnpCameraInfo info;
    EXPECT(EOPNP_OK, eopnp_model_camera(model, 3, &c3));
    EXPECT(EOPNP_OK, eopnp_camera_info(c3, &info));
    eopnp_camera_free(c3);
    CHECK(reg.focal_error_pct == 100.0 * fabs(reg.solution.focal_x - info.fx) / info.fx);
  }
  /* NULL and all-zero intrinsics: plain registration. */
  EopnpRegistration plain, with;
  EopnpFreeIntrinsics no_free = {0};
  EXPECT(EOPNP_OK, eopnp_model_register(model, ids[2], s, NULL, &plain));
  CHECK(!plain.has_focal_error && plain.focal_error_pct == 0.0 && !plain.solution.camera_estimated);
  memset(&with, 0xff, sizeof with);
  EXPECT(EOPNP_OK, eopnp_model_register_with(model, ids[2], s, NULL, NULL, &with));
  CHECK(memcmp(with.solution.rotation, plain.solution.rotation, sizeof plain.solution.rotation) == 0);
  CHECK(!with.has_focal_error && with.focal_error_pct == 0.0 && !with.solution.focal_estimated);
  memset(&with, 0xff, sizeof with);
  EXPECT(EOPNP_OK, eopnp_model_register_with(model, ids[2], s, NULL, &no_free, &with));
  CHECK(memcmp(with.solution.translation, plain.solution.translation,
               sizeof plain.solution.translation) == 0);
  CHECK(!with.has_focal_error && !with.solution.camera_estimated);
  /* The distortion refined, the focal length known: its error 0. */
  EopnpFreeIntrinsics dist = {0};
  dist.refine_distortion = true;
  EXPECT(EOPNP_OK, eopnp_model_register_with(model, ids[0], s, r, &dist, &with));
  CHECK(with.has_ransac && with.has_focal_error && with.focal_error_pct == 0.0);
  CHECK(with.solution.camera_estimated && !with.solution.focal_estimated);
  /* Bad options: a range min > max, a range without unknown_focal. */
  fi.focal_min_px = 2000.0;
  fi.focal_max_px = 1000.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_model_register_with(model, ids[0], s, NULL, &fi, &with));
  CHECK(strstr(eopnp_last_error_message(), "unknown focal length") != NULL);
  fi.unknown_focal = false;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_model_register_with(model, ids[0], s, NULL, &fi, &with));
  CHECK(strstr(eopnp_last_error_message(), "unknown_focal") != NULL);
  fi.unknown_focal = true;
  EXPECT(EOPNP_INVALID_OPTION,
         eopnp_model_register_batch_with(model, ids, 6, s, NULL, &fi, 2, regs, statuses));
  for (int i = 0; i < 6; ++i) CHECK(statuses[i] == EOPNP_INVALID_OPTION);
  EXPECT(EOPNP_REGISTER_ERROR, eopnp_model_register_with(model, 12345, s, NULL, &fi, &with));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_with(NULL, ids[0], s, NULL, &fi, &with));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_with(model, ids[0], s, NULL, &fi, NULL));
  /* The batch: one call at a time. */
  fi.focal_min_px = 0.0;
  fi.focal_max_px = 0.0;
  EXPECT(EOPNP_OK, eopnp_model_register_batch_with(model, ids, 6, s, r, &fi, 2, regs, statuses));
  for (int i = 0; i < 6; ++i) {
    CHECK(statuses[i] == EOPNP_OK && regs[i].has_focal_error && regs[i].focal_error_pct < 0.01);
    EXPECT(EOPNP_OK, eopnp_model_register_with(model, ids[i], s, r, &fi, &with));
    CHECK(memcmp(&with.focal_error_pct, &regs[i].focal_error_pct, sizeof with.focal_error_pct) == 0);
    CHECK(memcmp(with.solution.rotation, regs[i].solution.rotation,
                 sizeof with.solution.rotation) == 0);
  }
  EXPECT(EOPNP_NULL_POINTER,
         eopnp_model_register_batch_with(model, ids, 6, s, NULL, &fi, 1, NULL, statuses));
  eopnp_ransac_free(r);
  eopnp_solver_free(s);
  eopnp_model_free(model);
  eopnp_model_free(NULL);

  EopnpModel *none = NULL;
  EXPECT(EOPNP_MODEL_ERROR, eopnp_model_read("/nonexistent/eopnp-model", &none));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_read(NULL, &none));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_read(dir, NULL));
  CHECK(none == NULL);
}

static void test_frames(const char *dir) {
  EopnpModel *model = NULL;
  EopnpSolver *s = NULL;
  EopnpRansac *r = NULL;
  EXPECT(EOPNP_OK, eopnp_model_read(dir, &model));
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EXPECT(EOPNP_OK, eopnp_ransac_create(&r));
  size_t count = 0;
  EXPECT(EOPNP_BUFFER_TOO_SMALL, eopnp_model_frame_ids(model, NULL, 0, &count));
  CHECK(count == 6);
  uint32_t ids[6];
  EXPECT(EOPNP_OK, eopnp_model_frame_ids(model, ids, 6, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_frame_ids(model, ids, 6, NULL));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_frame_ids(model, NULL, 6, &count));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_frame_ids(NULL, ids, 6, &count));
  EopnpFrameRegistration f;
  EXPECT(EOPNP_OK, eopnp_model_register_frame(model, ids[0], s, NULL, &f));
  CHECK(f.frame_id == ids[0] && f.images >= 2 && !f.has_ransac && f.rotation_error_deg < 1.0);
  EXPECT(EOPNP_OK, eopnp_model_register_frame(model, ids[1], s, r, &f));
  CHECK(f.has_ransac && f.ransac.iterations >= 1 && f.inliers > 0);
  EXPECT(EOPNP_REGISTER_ERROR, eopnp_model_register_frame(model, 4242, s, NULL, &f));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_frame(NULL, ids[0], s, NULL, &f));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_frame(model, ids[0], NULL, NULL, &f));
  EXPECT(EOPNP_NULL_POINTER, eopnp_model_register_frame(model, ids[0], s, NULL, NULL));
  eopnp_ransac_free(r);
  eopnp_solver_free(s);
  eopnp_model_free(model);
}

/* Several threads solve with one shared solver and camera at once; each fails in its own way
 * in between, and its last error is its own. */
typedef struct {
  int id;
  const EopnpSolver *solver;
  const EopnpCamera *camera;
  int errors;
} Worker;

static void *work(void *arg) {
  Worker *w = arg;
  EopnpProblem p = normalised(N);
  p.image = PX;
  p.camera = w->camera;
  EopnpSolution first, out;
  if (eopnp_solve(w->solver, &p, &first) != EOPNP_OK) ++w->errors;
  char want[64];
  snprintf(want, sizeof want, "got %d, need at least 4", w->id);
  for (int i = 0; i < 300; ++i) {
    EopnpProblem bad = p;
    bad.n = (size_t)w->id; /* 0 .. 3: too few */
    if (eopnp_solve(w->solver, &bad, &out) != EOPNP_TOO_FEW_POINTS) ++w->errors;
    if (eopnp_solve(w->solver, &p, &out) != EOPNP_OK) ++w->errors;
    /* The fields, not the whole struct: its padding bytes are not part of the result. */
    if (memcmp(out.rotation, first.rotation, sizeof out.rotation) != 0 ||
        memcmp(out.translation, first.translation, sizeof out.translation) != 0 ||
        memcmp(&out.cost, &first.cost, sizeof out.cost) != 0)
      ++w->errors;
    if (strstr(eopnp_last_error_message(), want) == NULL) ++w->errors;
  }
  return NULL;
}

static void test_threads(void) {
  EopnpSolver *s = NULL;
  EopnpCamera *cam = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  EXPECT(EOPNP_OK, eopnp_camera_pinhole(800.0, 800.0, 320.0, 240.0, &cam));
  pthread_t threads[4];
  Worker workers[4];
  for (int i = 0; i < 4; ++i) {
    workers[i] = (Worker){i, s, cam, 0};
    CHECK(pthread_create(&threads[i], NULL, work, &workers[i]) == 0);
  }
  for (int i = 0; i < 4; ++i) {
    pthread_join(threads[i], NULL);
    CHECK(workers[i].errors == 0);
  }
  eopnp_camera_free(cam);
  eopnp_solver_free(s);
}

/* The known vertical and the unknown focal length (EopnpProblem's gravity_* and unknown_focal
 * fields, EopnpSolution's focal_*). The synthetic problem's pose is R = I, so the vertical is
 * the same vector in both frames. */
static void test_focal_and_gravity(void) {
  EopnpSolver *s = NULL;
  EopnpCamera *guess = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  /* The pixels are of an 800 px camera; the guess is 500 px. */
  EXPECT(EOPNP_OK, eopnp_camera_pinhole(500.0, 500.0, 320.0, 240.0, &guess));
  EopnpProblem p = normalised(N);
  p.image = PX;
  p.camera = guess;
  EopnpSolution sol;
  memset(&sol, 0xff, sizeof sol);
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(!sol.focal_estimated && sol.focal_x == 0.0 && sol.focal_y == 0.0);
  CHECK(sol.reprojection_rmse * 500.0 > 1.0); /* the wrong focal length does not fit */
  p.unknown_focal = true;
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(sol.focal_estimated);
  CHECK(fabs(sol.focal_x - 800.0) < 1e-6 && fabs(sol.focal_y - 800.0) < 1e-6);
  CHECK(fabs(sol.translation[2] - 6.0) < 1e-6 && fabs(sol.translation[0] - 0.1) < 1e-6);
  CHECK(fabs(sol.rotation[0] - 1.0) < 1e-9);
  /* Within a range; a bad range; a range without the option. */
  p.focal_min_px = 400.0;
  p.focal_max_px = 1000.0;
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(fabs(sol.focal_x - 800.0) < 1e-6);
  p.focal_min_px = 1000.0;
  p.focal_max_px = 400.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &p, &sol));
  CHECK(strstr(eopnp_last_error_message(), "unknown focal length") != NULL);
  p.unknown_focal = false;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &p, &sol));
  CHECK(strstr(eopnp_last_error_message(), "unknown_focal") != NULL);
  /* Normalised input cannot have it. */
  EopnpProblem q = normalised(N);
  q.unknown_focal = true;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &q, &sol));

  /* The vertical: right, then 10 degrees off at 0.1 degree. */
  const double down[3] = {0.0, 0.0, -9.81};
  /* sin and cos of 10 degrees (literals: the shared library's test does not link libm). */
  const double tilted[3] = {0.0, 0.17364817766693033, -0.984807753012208};
  const double zero[3] = {0.0, 0.0, 0.0};
  EopnpProblem g = normalised(N);
  g.gravity_camera = down;
  g.gravity_world = down;
  g.gravity_sigma_deg = 0.5;
  EXPECT(EOPNP_OK, eopnp_solve(s, &g, &sol));
  CHECK(fabs(sol.rotation[0] - 1.0) < 1e-9 && fabs(sol.translation[2] - 6.0) < 1e-9);
  CHECK(!sol.focal_estimated);
  g.gravity_camera = tilted;
  g.gravity_sigma_deg = 0.1;
  EXPECT(EOPNP_GRAVITY_MISMATCH, eopnp_solve(s, &g, &sol));
  CHECK(strcmp(eopnp_status_name(EOPNP_GRAVITY_MISMATCH), "EOPNP_GRAVITY_MISMATCH") == 0);
  {
    /* "... the pose they give is A degrees off it, S standard deviations ..." */
    const char *msg = eopnp_last_error_message();
    const char *at = strstr(msg, " is ");
    double angle = 0.0, sigmas = 0.0;
    CHECK(at != NULL && strstr(msg, "contradict") != NULL);
    if (at != NULL) {
      CHECK(sscanf(at, " is %lf degrees off it, %lf standard deviations", &angle, &sigmas) == 2);
    }
    CHECK(fabs(angle - 10.0) < 0.1);
    CHECK(sigmas > 3.0);
  }
  /* Bad verticals: sigma, zero direction, half given, sigma alone; with unknown focal. */
  g.gravity_sigma_deg = 0.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &g, &sol));
  g.gravity_sigma_deg = -1.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &g, &sol));
  g.gravity_sigma_deg = NAN;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &g, &sol));
  CHECK(strstr(eopnp_last_error_message(), "sigma_deg") != NULL);
  g.gravity_sigma_deg = 1.0;
  g.gravity_camera = zero;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &g, &sol));
  g.gravity_camera = down;
  g.gravity_world = NULL;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &g, &sol));
  g.gravity_camera = NULL;
  EXPECT(EOPNP_INVALID_ARGUMENT, eopnp_solve(s, &g, &sol));
  p.gravity_camera = down;
  p.gravity_world = down;
  p.gravity_sigma_deg = 1.0;
  p.unknown_focal = true;
  p.focal_min_px = 0.0;
  p.focal_max_px = 0.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &p, &sol));
  eopnp_camera_free(guess);
  eopnp_solver_free(s);
}

/* The refined principal point and distortion (EopnpProblem's refine_principal_point and
 * refine_distortion, EopnpSolution's camera_*): a SIMPLE_RADIAL camera recovered from a guess
 * with its principal point off and no distortion, on 30 points over a wide field of view (the
 * Rust tests compare with the library bit for bit); the camera fields zero when nothing is
 * free; EOPNP_INVALID_OPTION naming the option for normalised or rig input or with a vertical;
 * EOPNP_TOO_FEW_POINTS for fewer points than half the free parameters. */
#define NW 30
static void test_refined_intrinsics(void) {
  static const double truth[4] = {500.0, 318.0, 243.0, -0.08}; /* f, cx, cy, k */
  double w[3 * NW], px[2 * NW], m[2 * NW];
  for (int i = 0; i < NW; ++i) {
    const double x = -2.0 + 0.8 * (i % 6), y = -1.5 + 0.75 * ((i / 6) % 5);
    const double z = 4.0 + 0.4 * ((7 * i) % 11);
    /* The pose R = I, t = (0.1, -0.2, 0.3): world = camera - t. */
    w[3 * i] = x - 0.1;
    w[3 * i + 1] = y + 0.2;
    w[3 * i + 2] = z - 0.3;
    const double u = x / z, v = y / z, d = 1.0 + truth[3] * (u * u + v * v);
    m[2 * i] = u;
    m[2 * i + 1] = v;
    px[2 * i] = truth[0] * d * u + truth[1];
    px[2 * i + 1] = truth[0] * d * v + truth[2];
  }
  EopnpSolver *s = NULL;
  EopnpCamera *guess = NULL, *guess_f = NULL;
  EXPECT(EOPNP_OK, eopnp_solver_create(&s));
  const double g[4] = {500.0, 325.0, 236.0, 0.0};   /* the principal point 7 px off, k = 0 */
  const double gf[4] = {650.0, 325.0, 236.0, 0.0};  /* and the focal length 30 % off */
  EXPECT(EOPNP_OK, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, g, 4, &guess));
  EXPECT(EOPNP_OK, eopnp_camera_from_colmap("SIMPLE_RADIAL", 640, 480, gf, 4, &guess_f));
  EopnpProblem p = {0};
  p.n = NW;
  p.world = w;
  p.image = px;
  p.camera = guess;
  EopnpSolution sol;
  /* Nothing free: the camera fields zero. */
  memset(&sol, 0xff, sizeof sol);
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(!sol.camera_estimated && sol.camera_n_params == 0 && !sol.focal_estimated);
  {
    int zeros = 1;
    for (int j = 0; j < EOPNP_MAX_CAMERA_PARAMS; ++j) zeros = zeros && sol.camera_params[j] == 0.0;
    CHECK(zeros);
  }
  CHECK(sol.cost > 1.0); /* the guess does not fit */
  /* The principal point and the distortion, the focal length known. */
  p.refine_principal_point = true;
  p.refine_distortion = true;
  memset(&sol, 0xff, sizeof sol);
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(sol.camera_estimated && sol.camera_n_params == 4);
  CHECK(!sol.focal_estimated && sol.focal_x == 0.0 && sol.focal_y == 0.0);
  CHECK(sol.camera_params[0] == 500.0); /* known: the guess's, exactly */
  for (int j = 1; j < 4; ++j) CHECK(fabs(sol.camera_params[j] - truth[j]) < 1e-6);
  for (int j = 4; j < EOPNP_MAX_CAMERA_PARAMS; ++j) CHECK(sol.camera_params[j] == 0.0);
  CHECK(fabs(sol.translation[0] - 0.1) < 1e-6 && fabs(sol.translation[2] - 0.3) < 1e-6);
  CHECK(fabs(sol.rotation[0] - 1.0) < 1e-9);
  CHECK(sol.cost < 1e-12);
  /* With the focal length unknown too: focal_x is the camera's first parameter. */
  p.camera = guess_f;
  p.unknown_focal = true;
  memset(&sol, 0xff, sizeof sol);
  EXPECT(EOPNP_OK, eopnp_solve(s, &p, &sol));
  CHECK(sol.camera_estimated && sol.camera_n_params == 4 && sol.focal_estimated);
  CHECK(sol.focal_x == sol.camera_params[0] && sol.focal_y == sol.focal_x);
  for (int j = 0; j < 4; ++j) CHECK(fabs(sol.camera_params[j] - truth[j]) < 1e-6);
  /* Too few points: 6 pose + 1 focal + 2 + 1 parameters need 5 points. */
  p.n = 4;
  EXPECT(EOPNP_TOO_FEW_POINTS, eopnp_solve(s, &p, &sol));
  CHECK(strstr(eopnp_last_error_message(), "need at least 5") != NULL);
  p.n = NW;
  p.unknown_focal = false;
  p.camera = guess;
  /* Normalised input. */
  EopnpProblem q = p;
  q.camera = NULL;
  q.image = m;
  q.refine_principal_point = false;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &q, &sol));
  CHECK(strstr(eopnp_last_error_message(), "`refine_distortion`") != NULL);
  q.refine_principal_point = true;
  q.refine_distortion = false;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &q, &sol));
  CHECK(strstr(eopnp_last_error_message(), "`refine_principal_point`") != NULL);
  /* A rig of the one camera. */
  EopnpRig *rig = NULL;
  const EopnpCamera *cams[1] = {guess};
  EopnpPose identity = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}};
  EXPECT(EOPNP_OK, eopnp_rig_create(cams, &identity, 1, &rig));
  uint32_t which[NW] = {0};
  q = p;
  q.camera = NULL;
  q.rig = rig;
  q.rig_cameras = which;
  q.refine_principal_point = false;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &q, &sol));
  CHECK(strstr(eopnp_last_error_message(), "`refine_distortion`") != NULL);
  q.refine_distortion = false;
  EXPECT(EOPNP_OK, eopnp_solve(s, &q, &sol)); /* the rig problem itself is fine */
  eopnp_rig_free(rig);
  /* A vertical. */
  const double down[3] = {0.0, 1.0, 0.0};
  q = p;
  q.refine_distortion = false;
  q.gravity_camera = down;
  q.gravity_world = down;
  q.gravity_sigma_deg = 1.0;
  EXPECT(EOPNP_INVALID_OPTION, eopnp_solve(s, &q, &sol));
  CHECK(strstr(eopnp_last_error_message(), "`refine_principal_point`") != NULL);
  CHECK(strstr(eopnp_last_error_message(), "without a known vertical") != NULL);
  eopnp_camera_free(guess_f);
  eopnp_camera_free(guess);
  eopnp_solver_free(s);
}

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s REFERENCE_FILE COLMAP_MODEL_DIR COLMAP_RIG_MODEL_DIR\n", argv[0]);
    return 2;
  }
  make_problem();
  test_errors_and_version();
  test_solver_options();
  test_ransac_options();
  test_cameras();
  test_solves();
  test_focal_and_gravity();
  test_refined_intrinsics();
  test_model(argv[2]);
  test_frames(argv[3]);
  test_threads();
  test_reference(argv[1]);
  printf("%d checks, %d failed\n", checks, failures);
  return failures == 0 ? 0 : 1;
}
