//! The `eopnp` command line: `eopnp register` (a COLMAP model's poses re-estimated and
//! compared with the model's) and `eopnp solve` (one problem from a CSV or JSON file). The
//! binary (`src/main.rs`) is a thin `main` around [`run`]; [`input`] is public for the fuzz
//! harness (`fuzz/src/harness.rs`). Not a stable library API: use the `eopnp` crate.

mod experiment;
pub mod input;
mod register;
mod report;
pub mod solve;
mod source;

use std::io::Write;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use eopnp::{Refinement, Solver};

/// Camera pose from 2D-3D point correspondences (EOPnP, Zhou & Kaess 2019, plus a
/// reprojection-error refinement).
///
/// Without arguments, re-estimates the poses of the COLMAP reconstruction bundled with the
/// repository (data/colmap-boxes) and explains the output.
///
/// Exit codes: 0 success, 1 the solver failed on valid input, 2 bad input or arguments.
#[derive(Debug, Parser)]
#[command(name = "eopnp", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Re-estimate every image's pose of a COLMAP model from its 2D-3D correspondences and
    /// compare with the model's (bundle-adjusted) pose.
    Register(RegisterArgs),
    /// Solve one PnP problem from a CSV or JSON file of correspondences; prints the pose as
    /// JSON.
    #[command(long_about = SOLVE_HELP)]
    Solve(SolveArgs),
}

const SOLVE_HELP: &str =
    "Solve one PnP problem from a file of correspondences, or from standard input if FILE is
`-`; prints the pose as JSON.

Input formats (chosen by --format; otherwise by the extension .csv or .json; otherwise, and
for standard input, by content: JSON if it starts with `{`):

  CSV: a header naming the columns x, y, X, Y, Z (pixel x, pixel y and the 3D point X, Y, Z;
  names case-sensitive, in any order), then one correspondence per line. The separator is
  `,`, `;` or a tab, whichever splits the header into those five names. Fields may be quoted
  (\"x\",\"y\",...) and surrounding spaces are ignored; a UTF-8 byte-order mark is accepted.
  Blank lines and lines starting with # are ignored. The camera is given with --camera.

  JSON: {\"camera\": {\"model\": \"SIMPLE_RADIAL\", \"params\": [1245.65, 600, 800, 0.0577]},
         \"points2d\": [[x, y], ...], \"points3d\": [[X, Y, Z], ...]}
  (--camera, if given, replaces the file's camera.)

The input must be a regular file or standard input (a FIFO, a device or a directory is
refused). Inputs larger than --max-input-size (default 1 GiB) are refused, and so are CSV
lines (comments excepted) and JSON strings or numbers longer than 64 KiB.

Camera models and parameter orders are COLMAP's: SIMPLE_PINHOLE f,cx,cy; PINHOLE fx,fy,cx,cy;
SIMPLE_RADIAL f,cx,cy,k; RADIAL f,cx,cy,k1,k2; OPENCV fx,fy,cx,cy,k1,k2,p1,p2; OPENCV_FISHEYE
fx,fy,cx,cy,k1,k2,k3,k4; FULL_OPENCV fx,fy,cx,cy,k1,k2,p1,p2,k3,k4,k5,k6; SIMPLE_RADIAL_FISHEYE
f,cx,cy,k; RADIAL_FISHEYE f,cx,cy,k1,k2.

Output: rotation (matrix, row-major, and quaternion w,x,y,z) and translation of the
world-to-camera pose x_cam = R X + t, number of points and inliers, the minimised cost and the
reprojection RMSE in pixels; with --unknown-focal the estimated \"focal\": [fx, fy] (and the
estimated camera), with a known vertical (--gravity-camera, --gravity-world, --gravity-sigma)
a \"gravity\" block with the angle between the measured vertical and the pose's.";

/// Options of `register`.
#[derive(Debug, Args)]
pub(crate) struct RegisterArgs {
    /// COLMAP model directory: cameras, images and points3D in text (.txt) or binary (.bin)
    /// format (binary is used if both are present), and for a model with rigs (COLMAP 3.12
    /// and later) rigs and frames: if a frame holds several images, every frame is registered
    /// as one rig pose (see --per-image).
    model_dir: PathBuf,
    #[command(flatten)]
    opts: RegisterOptions,
    /// Write the model with every image's pose replaced by the re-estimated one (images that
    /// fail keep their pose, and the output says which; with frames of several images every
    /// frame's pose, and its images' poses composed from it; with frames of one image each,
    /// each registered image's frame too) to the directory OUT, which must not
    /// exist (its parent must) or be empty, and must not be the input's directory. Written
    /// atomically: into a temporary directory next to OUT, fsynced, then renamed to OUT (into an
    /// existing empty OUT: temporary files renamed into place); on any failure nothing is left.
    #[arg(long, value_name = "OUT")]
    write: Option<PathBuf>,
    /// Format of the model written by --write (default: the input model's format).
    #[arg(long, value_name = "FORMAT", requires = "write")]
    write_format: Option<WriteFormat>,
}

/// The format of `register --write`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum WriteFormat {
    /// cameras.txt, images.txt, points3D.txt (and rigs.txt, frames.txt).
    Text,
    /// cameras.bin, images.bin, points3D.bin (and rigs.bin, frames.bin).
    Binary,
}

/// Estimation options shared by `register` and the no-argument default run.
#[derive(Debug, Args, Clone)]
pub(crate) struct RegisterOptions {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Use the paper's algebraic cost only (no reprojection-error refinement).
    #[arg(long)]
    algebraic: bool,
    /// Robust estimation: RANSAC with P3P hypotheses, EOPnP local optimisation and final fit
    /// (`eopnp::ransac`). The inliers column is RANSAC's inlier count.
    #[arg(long)]
    ransac: bool,
    /// RANSAC inlier threshold on the pixel reprojection error.
    #[arg(long, value_name = "PX", default_value_t = 4.0)]
    threshold: f64,
    /// Replace this fraction (0 to 1) of each image's correspondences by wrong 3D points
    /// (random points of the model's cloud plus Gaussian noise of 0.5 model units, seeded by
    /// --seed and the image id), to test robustness. The errors of EOPnP on the true
    /// correspondences alone (the floor) are reported alongside.
    #[arg(long, value_name = "FRACTION")]
    outliers: Option<f64>,
    /// Seed of the outlier injection and of RANSAC's sampling.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// Write each image's problem (camera, pixels, 3D points with the injected outliers, true
    /// correspondence mask, model pose) as JSON to FILE, e.g. for scripts/compare_poselib.py.
    #[arg(long, value_name = "FILE")]
    export_problems: Option<PathBuf>,
    /// Refuse model files larger than SIZE: bytes, or with a suffix K, M, G or T (powers of
    /// 1024; `KiB` etc. also accepted), or `none`. Default: none (the model is streamed and
    /// memory stays proportional to it). Images with more than 1,000,000 observations and 3D
    /// points with tracks longer than 1,000,000 are refused.
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    max_input_size: Option<u64>,
    /// On a model whose frames hold several images, register every image on its own, as on a
    /// model without rigs, instead of every frame as one rig pose (not with --write: the
    /// frames' poses would disagree with their images').
    #[arg(long)]
    per_image: bool,
    /// Withhold every image's focal length: it is estimated with the pose (also with --ransac,
    /// whose samples are then P4Pf's four points), the model's camera being only the starting
    /// guess (see --focal-guess-scale; principal point and distortion as the model's). Each
    /// image's estimated focal length and its error against the model's are reported, with
    /// their median and maximum. Image by image: on a model whose frames hold several images,
    /// add --per-image. Not with --write (the model's cameras would not match the poses).
    #[arg(long, conflicts_with = "write")]
    unknown_focal: bool,
    /// With --unknown-focal: start from the model's focal length times S (finite, > 0), to
    /// check the recovery from a wrong guess [default: 1].
    #[arg(
        long,
        value_name = "S",
        requires = "unknown_focal",
        allow_hyphen_values = true
    )]
    focal_guess_scale: Option<f64>,
}

impl Default for RegisterOptions {
    fn default() -> Self {
        RegisterOptions {
            json: false,
            algebraic: false,
            ransac: false,
            threshold: 4.0,
            outliers: None,
            seed: 0,
            export_problems: None,
            max_input_size: None,
            per_image: false,
            unknown_focal: false,
            focal_guess_scale: None,
        }
    }
}

impl RegisterOptions {
    /// Checks the values clap cannot.
    fn validate(&self) -> Result<(), Failure> {
        // RANSAC compares squared errors with the squared threshold, which must be a normal
        // number (as `Ransac` checks).
        let t2 = self.threshold * self.threshold;
        if !(self.threshold.is_finite() && self.threshold > 0.0 && t2.is_normal()) {
            return Err(Failure::input(format!(
                "--threshold must be a positive number of pixels whose square is a normal \
                 number (between about 1e-154 and 1e154), got {}",
                self.threshold
            )));
        }
        if let Some(s) = self.focal_guess_scale {
            if !(s > 0.0 && s.is_finite()) {
                return Err(Failure::input(format!(
                    "--focal-guess-scale must be a finite number > 0, got {s}"
                )));
            }
        }
        if let Some(f) = self.outliers {
            if !(0.0..=1.0).contains(&f) {
                return Err(Failure::input(format!(
                    "--outliers must be a fraction between 0 and 1, got {f}"
                )));
            }
        }
        Ok(())
    }

    fn solver(&self) -> Solver {
        if self.algebraic {
            Solver::default().refinement(Refinement::Algebraic)
        } else {
            Solver::default()
        }
    }
}

/// Options of `solve`.
#[derive(Debug, Args)]
struct SolveArgs {
    /// Correspondence file (.csv or .json), or `-` for standard input (`./-` is a file named
    /// `-`).
    file: PathBuf,
    /// Input format; by default from the extension, or for standard input and other
    /// extensions from the content.
    #[arg(long, value_enum)]
    format: Option<input::Format>,
    /// Camera as "MODEL P1 P2 ...", e.g. "SIMPLE_RADIAL 1245.65 600 800 0.0577" (COLMAP's model
    /// names and parameter orders). Required for CSV input.
    #[arg(long, allow_hyphen_values = true)]
    camera: Option<String>,
    /// Use the paper's algebraic cost only (no reprojection-error refinement).
    #[arg(long)]
    algebraic: bool,
    /// Refuse inputs larger than SIZE: bytes, or with a suffix K, M, G or T (powers of 1024;
    /// `KiB` etc. also accepted), or `none`.
    #[arg(long, value_name = "SIZE", value_parser = parse_size, default_value = "1G")]
    max_input_size: u64,
    /// The focal length is unknown: estimated with the pose, the camera's (--camera or the
    /// file's) being only the starting guess (its principal point and distortion are kept; a
    /// camera's two focal lengths are scaled alike). Searched between a tenth and ten times
    /// the guess unless --focal-range is given. The output gains "focal": [fx, fy] and its
    /// "camera" shows the estimated camera.
    #[arg(long, conflicts_with = "gravity_camera")]
    unknown_focal: bool,
    /// With --unknown-focal: search the (first) focal length between MIN_PX and MAX_PX pixels
    /// (0 < MIN_PX < MAX_PX).
    #[arg(
        long,
        num_args = 2,
        value_names = ["MIN_PX", "MAX_PX"],
        requires = "unknown_focal",
        allow_hyphen_values = true
    )]
    focal_range: Option<Vec<f64>>,
    /// A known vertical: the direction of gravity (or any direction known in both frames)
    /// measured in the camera's frame, as X,Y,Z (any non-zero length). Needs --gravity-world
    /// and --gravity-sigma. The pose is then the maximum a posteriori one with the vertical as
    /// a prior; images that contradict it are an error (exit 2).
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_parser = parse_vector,
        allow_hyphen_values = true,
        requires_all = ["gravity_world", "gravity_sigma"]
    )]
    gravity_camera: Option<nalgebra::Vector3<f64>>,
    /// The same direction in the world's frame, X,Y,Z (e.g. 0,0,-1 for "down" in a z-up
    /// world). Needs --gravity-camera and --gravity-sigma.
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_parser = parse_vector,
        allow_hyphen_values = true,
        requires_all = ["gravity_camera", "gravity_sigma"]
    )]
    gravity_world: Option<nalgebra::Vector3<f64>>,
    /// The standard deviation of the measured direction, degrees (finite, > 0; an IMU's tilt
    /// accuracy, e.g. 0.1 to 1). Needs --gravity-camera and --gravity-world.
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires_all = ["gravity_camera", "gravity_world"]
    )]
    gravity_sigma: Option<f64>,
    /// Refine the principal point with the pose (and the focal length with --unknown-focal),
    /// the camera's being the starting guess (COLMAP's refine_principal_point). The output's
    /// "camera" shows the refined camera. Not with a known vertical.
    #[arg(long, conflicts_with = "gravity_camera")]
    refine_principal_point: bool,
    /// Refine the camera's distortion parameters with the pose (and the focal length with
    /// --unknown-focal), the camera's being the starting guess (COLMAP's refine_extra_params).
    /// The output's "camera" shows the refined camera. Not with a known vertical.
    #[arg(long, conflicts_with = "gravity_camera")]
    refine_distortion: bool,
}

/// Parses a vector `X,Y,Z` of three finite numbers.
pub(crate) fn parse_vector(s: &str) -> Result<nalgebra::Vector3<f64>, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || format!("`{s}`: expected three finite numbers X,Y,Z, e.g. 0,0,-1");
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (x, p) in v.iter_mut().zip(&parts) {
        *x = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(bad)?;
    }
    Ok(nalgebra::Vector3::new(v[0], v[1], v[2]))
}

impl SolveArgs {
    /// The unknown focal length and the vertical of `solve`, checked.
    fn solve_options(&self) -> Result<solve::Options, Failure> {
        let unknown_focal = match (&self.focal_range, self.unknown_focal) {
            (Some(r), _) => {
                let (lo, hi) = (r[0], r[1]);
                if !(lo > 0.0 && hi > lo && hi.is_finite()) {
                    return Err(Failure::input(format!(
                        "--focal-range: expected 0 < MIN_PX < MAX_PX, finite, got {lo} {hi}"
                    )));
                }
                Some(Some((lo, hi)))
            }
            (None, true) => Some(None),
            (None, false) => None,
        };
        let gravity = match (self.gravity_camera, self.gravity_world, self.gravity_sigma) {
            (Some(c), Some(w), Some(sigma)) => {
                Some(eopnp::Gravity::new(c, w, sigma).map_err(|_| {
                    Failure::input(format!(
                        "--gravity-camera {}, --gravity-world {}, --gravity-sigma {sigma}: the \
                         two directions must be non-zero and the sigma a finite number of \
                         degrees > 0",
                        vector_text(&c),
                        vector_text(&w)
                    ))
                })?)
            }
            _ => None,
        };
        Ok(solve::Options {
            unknown_focal,
            refine_principal_point: self.refine_principal_point,
            refine_distortion: self.refine_distortion,
            gravity,
        })
    }
}

/// `v` as `X,Y,Z`.
fn vector_text(v: &nalgebra::Vector3<f64>) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

/// Parses a size: bytes, or a number with a suffix K, M, G or T (powers of 1024, optionally
/// followed by `iB` or `B`), or `none` (no limit).
pub(crate) fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    if t.eq_ignore_ascii_case("none") {
        return Ok(u64::MAX);
    }
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, suffix) = t.split_at(digits);
    let shift = match suffix.trim_start().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => {
            return Err(format!(
                "`{s}`: expected bytes, or a number with a suffix K, M, G or T (powers of 1024), \
                 or `none`"
            ))
        }
    };
    number
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(1 << shift))
        .ok_or_else(|| format!("`{s}`: expected a whole number of bytes below 2^64"))
}

/// A failure: the message for stderr and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// What went wrong (file, line and reason for input errors).
    pub message: String,
    /// Process exit code: 1 solver failure, 2 bad input.
    pub code: u8,
}

impl Failure {
    pub(crate) fn input(message: impl Into<String>) -> Self {
        Failure {
            message: message.into(),
            code: 2,
        }
    }

    pub(crate) fn solver(message: impl Into<String>) -> Self {
        Failure {
            message: message.into(),
            code: 1,
        }
    }
}

/// `s` for the terminal: control and other invisible characters escaped as Rust escapes
/// them (`\u{1b}`, `\t`, `\u{200b}`), everything else as it is. For names read from input
/// files (COLMAP image names, paths), so that no escape sequence reaches the terminal raw.
pub(crate) fn escaped(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if matches!(c, '\\' | '"' | '\'') || c.escape_debug().count() == 1 {
            out.push(c);
        } else {
            out.extend(c.escape_debug());
        }
    }
    out
}

/// Writes `text` to stdout; a closed pipe (e.g. `| head`) is not an error.
pub(crate) fn emit(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Failure::solver(format!("cannot write output: {e}"))),
    }
}

/// The bundled model (`data/colmap-boxes` of the repository, this crate's parent directory).
fn bundled_model() -> PathBuf {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .unwrap_or(manifest)
        .join("data/colmap-boxes")
}

/// Runs the command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        None => register::run(&bundled_model(), &RegisterOptions::default(), None, true),
        Some(Command::Register(a)) => {
            let out = a.write.map(|dir| register::Output {
                dir,
                format: a.write_format.map(|f| match f {
                    WriteFormat::Text => eopnp::colmap::ModelFormat::Text,
                    WriteFormat::Binary => eopnp::colmap::ModelFormat::Binary,
                }),
            });
            register::run(&a.model_dir, &a.opts, out.as_ref(), false)
        }
        Some(Command::Solve(a)) => {
            let solver = if a.algebraic {
                Solver::default().refinement(Refinement::Algebraic)
            } else {
                Solver::default()
            };
            let limits = input::Limits {
                max_input_bytes: a.max_input_size,
                ..input::Limits::default()
            };
            let options = a.solve_options()?;
            let problem = input::read_problem(&a.file, a.format, a.camera.as_deref(), &limits)?;
            let json = solve::solve_with(&problem, &solver, &options)?;
            emit(&json)
        }
    }
}
