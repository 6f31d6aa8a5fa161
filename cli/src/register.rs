//! `eopnp register`: re-estimate every image's pose of a COLMAP model, or on a model with rigs
//! every frame's rig pose (`register/frames.rs`).

mod frames;

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::experiment::{self, ImageProblem, Outliers};
use eopnp::colmap::{
    self, Limit, Model, ModelErrorKind, ModelFormat, Pose, RegisterError, Registrar, SensorId,
};
use eopnp::ransac::Ransac;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use super::report::{format_name, to_json, to_table, Estimate, Extra, Row, Written};
use super::{emit, Failure, RegisterOptions};

/// Show the progress bar once a run has taken this long (short runs never show one).
const PROGRESS_AFTER: Duration = Duration::from_millis(500);

/// The standard deviation (model units) of the noise added to the injected wrong 3D points.
const OUTLIER_NOISE: f64 = 0.5;

impl super::RegisterOptions {
    fn outlier_spec(&self) -> Option<Outliers> {
        self.outliers.map(|fraction| Outliers {
            fraction,
            noise: OUTLIER_NOISE,
            seed: self.seed,
        })
    }

    /// `--focal-guess-scale`, 1 by default.
    fn focal_guess_scale(&self) -> f64 {
        self.focal_guess_scale.unwrap_or(1.0)
    }

    fn ransac_options(&self) -> Ransac {
        Ransac::default()
            .threshold_px(self.threshold)
            .seed(self.seed)
    }
}

/// One image's pose estimate: plain EOPnP on all correspondences, or with `--ransac` the
/// robust estimate, on the model's correspondences or, with `--outliers`, on a copy with
/// injected wrong 3D points.
fn estimate(
    registrar: &mut Registrar<'_>,
    model: &Model,
    image_id: u32,
    opts: &RegisterOptions,
) -> (Result<Estimate, RegisterError>, Option<Extra>) {
    // The solve is deterministic; the time reported is the best of three runs, as a shared
    // machine's scheduling noise otherwise dominates single ~1 ms measurements.
    let solver = opts.solver();
    let spec = opts.outlier_spec();
    // An unknown focal length: the solve is given the guess camera, and the library's
    // registrar (which solves through the model's camera) is not used.
    let guess = if opts.unknown_focal {
        let guess = model
            .image_and_camera(image_id)
            .and_then(|(_, cam)| experiment::focal_guess(cam, opts.focal_guess_scale()));
        match guess {
            Ok(g) => Some(g),
            Err(e) => return (Err(e), None),
        }
    } else {
        None
    };
    let guess = guess.as_ref();
    if spec.is_none() && guess.is_none() {
        let ransac = opts.ransac.then(|| opts.ransac_options());
        let mut run = || {
            registrar
                .register(image_id, &solver, ransac.as_ref())
                .map(Estimate::from)
        };
        let result = run().and_then(|mut best| {
            for _ in 0..2 {
                best.micros = best.micros.min(run()?.micros);
            }
            Ok(best)
        });
        // Without injected outliers every correspondence is a true one.
        let extra = result.as_ref().ok().and_then(|reg| {
            reg.ransac.map(|stats| Extra {
                stats: Some(stats),
                true_correspondences: reg.n,
                true_inliers: Some(reg.inliers),
                floor: None,
            })
        });
        return (result, extra);
    }
    let problem = experiment::image_problem(model, image_id, spec.as_ref());
    let floor = spec
        .is_some()
        .then(|| experiment::floor(model, image_id, &problem, &solver, guess).ok())
        .flatten();
    let mut extra = Extra {
        stats: None,
        true_correspondences: problem.truth.iter().filter(|b| **b).count(),
        true_inliers: None,
        floor,
    };
    let result = if opts.ransac {
        let r = opts.ransac_options();
        let run = || experiment::ransac_on_problem(model, image_id, &problem, &r, &solver, guess);
        run().and_then(|(mut best, sol)| {
            for _ in 0..2 {
                best.micros = best.micros.min(run()?.0.micros);
            }
            extra.true_inliers = Some(
                sol.inliers
                    .iter()
                    .zip(&problem.truth)
                    .filter(|(a, b)| **a && **b)
                    .count(),
            );
            extra.stats = Some(sol.stats);
            Ok(best)
        })
    } else {
        plain_on_problem(model, image_id, &problem, &solver, guess)
    };
    // Without injected outliers (an unknown focal length alone), the extras are those of the
    // registrar's path: RANSAC's statistics, or none.
    if spec.is_none() && !opts.ransac {
        return (result, None);
    }
    (result, Some(extra))
}

/// Plain EOPnP (no outlier rejection) on a problem with injected outliers, or with an unknown
/// focal length from `guess`.
fn plain_on_problem(
    model: &Model,
    image_id: u32,
    problem: &ImageProblem,
    solver: &eopnp::Solver,
    guess: Option<&eopnp::camera::Camera>,
) -> Result<Estimate, RegisterError> {
    let cam = model
        .images
        .get(&image_id)
        .and_then(|i| model.cameras.get(&i.camera_id))
        .ok_or(RegisterError::UnknownImage(image_id))?;
    let mut best = f64::INFINITY;
    let mut sol = None;
    for _ in 0..3 {
        let start = Instant::now();
        let s = solver.solve(&experiment::pixel_problem(
            &problem.world,
            &problem.pixels,
            cam,
            guess,
        ))?;
        best = best.min(start.elapsed().as_secs_f64() * 1e6);
        sol = Some(s);
    }
    let s = sol.ok_or(RegisterError::UnknownImage(image_id))?;
    let mut reg = experiment::estimate(model, image_id, problem, &s, s.used)?;
    reg.micros = best;
    Ok(reg)
}

/// The problems of `--export-problems` as JSON.
fn export_problems(model: &Model, opts: &RegisterOptions) -> String {
    let spec = opts.outlier_spec();
    let images: Vec<serde_json::Value> = model
        .images
        .iter()
        .filter_map(|(id, img)| {
            let cam = model.cameras.get(&img.camera_id)?;
            let p = experiment::image_problem(model, *id, spec.as_ref());
            let (r, t) = img.pose();
            Some(json!({
                "image_id": id,
                "name": img.name,
                "camera": {
                    "model": cam.model().name(),
                    "width": cam.width(),
                    "height": cam.height(),
                    "params": cam.params(),
                },
                "points2d": p.pixels.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>(),
                "points3d": p.world.iter().map(|x| [x.x, x.y, x.z]).collect::<Vec<_>>(),
                "truth": p.truth,
                "reference_rotation": [
                    [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                    [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                    [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
                ],
                "reference_translation": [t.x, t.y, t.z],
            }))
        })
        .collect();
    let v = json!({
        "outliers": opts.outliers.unwrap_or(0.0),
        "outlier_noise": OUTLIER_NOISE,
        "seed": opts.seed,
        "threshold_px": opts.threshold,
        "images": images,
    });
    let mut s = serde_json::to_string(&v).unwrap_or_default();
    s.push('\n');
    s
}

/// `--write OUT [--write-format F]`: where to write the re-estimated model.
#[derive(Clone, Debug)]
pub(crate) struct Output {
    /// The directory to create (or an existing empty one).
    pub(crate) dir: PathBuf,
    /// The format; `None`: the input's.
    pub(crate) format: Option<ModelFormat>,
}

/// Checks `--write OUT` before any work (exit code 2): OUT must not be, or be inside, the
/// input's directory (compared canonicalised, so symbolic links and `..` do not hide it), and
/// must be an empty directory or not exist with an existing parent directory.
fn check_output(input: &Path, out: &Path) -> Result<(), Failure> {
    let bad = |why: &str| Failure::input(format!("--write {}: {why}", out.display()));
    let input_c = std::fs::canonicalize(input)
        .map_err(|e| Failure::input(format!("{}: {e}", input.display())))?;
    let inside = |c: &Path| -> Result<(), Failure> {
        if c == input_c {
            Err(bad(
                "is the input model's directory (refusing to write over the input)",
            ))
        } else if c.starts_with(&input_c) {
            Err(bad("is inside the input model's directory"))
        } else {
            Ok(())
        }
    };
    match std::fs::metadata(out) {
        Ok(m) => {
            let c = std::fs::canonicalize(out).map_err(|e| bad(&e.to_string()))?;
            inside(&c)?;
            if !m.is_dir() {
                return Err(bad("exists and is not a directory"));
            }
            let mut entries = std::fs::read_dir(out).map_err(|e| bad(&e.to_string()))?;
            if entries.next().is_some() {
                return Err(bad(
                    "exists and is not empty (give a new directory or an empty one)",
                ));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let Some(name) = out.file_name() else {
                return Err(bad("not a directory name"));
            };
            let parent = match out.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            match std::fs::metadata(parent) {
                Ok(m) if m.is_dir() => {}
                Ok(_) => return Err(bad("its parent is not a directory")),
                Err(_) => return Err(bad("its parent directory does not exist")),
            }
            let c = std::fs::canonicalize(parent).map_err(|e| bad(&e.to_string()))?;
            inside(&c.join(name))
        }
        Err(e) => Err(bad(&e.to_string())),
    }
}

/// The input model with every registered image's pose replaced, written atomically to `out`.
fn write_output(
    model: &Model,
    input_format: ModelFormat,
    rows: &[Row],
    out: &Output,
) -> Result<Written, Failure> {
    let mut new = model.clone();
    let mut kept = Vec::new();
    let mut replaced = 0;
    let mut replaced_ids = std::collections::BTreeSet::new();
    for (id, _, result, _) in rows {
        match (result, new.images.get_mut(id)) {
            (Ok(reg), Some(img)) => {
                let q = reg.solution.pose().rotation;
                img.q = [q.w, q.i, q.j, q.k];
                img.t = reg.solution.translation;
                replaced += 1;
                replaced_ids.insert(*id);
            }
            _ => kept.push(*id),
        }
    }
    // Each registered image's frame (of this image alone: frames of several are refused
    // above) gets the pose that gives the image's: `rig_from_world = cam_from_rig^-1 *
    // cam_from_world`.
    for frame in new.frames.values_mut() {
        let mut ids = frame.image_ids();
        let (Some(id), None) = (ids.next(), ids.next()) else {
            continue;
        };
        drop(ids);
        if !replaced_ids.contains(&id) {
            continue;
        }
        let (Some(img), Some(rig)) = (new.images.get(&id), new.rigs.get(&frame.rig_id)) else {
            continue;
        };
        if let Some(cam_from_rig) = rig.sensor_from_rig(SensorId::camera(img.camera_id)) {
            let cam_from_world = Pose { q: img.q, t: img.t };
            frame.rig_from_world = Pose::from_isometry(
                &(cam_from_rig.isometry().inverse() * cam_from_world.isometry()),
            );
        }
    }
    let format = out.format.unwrap_or(input_format);
    write_model_to(&new, out, format)?;
    Ok(Written {
        dir: out.dir.clone(),
        format,
        replaced,
        kept,
    })
}

/// `model` written atomically to `out` in `format`; refusals are input errors (exit code 2).
fn write_model_to(model: &Model, out: &Output, format: ModelFormat) -> Result<(), Failure> {
    colmap::write_model(
        model,
        &out.dir,
        &colmap::WriteOptions::default().format(format),
    )
    .map_err(|e| {
        use std::io::ErrorKind as K;
        let message = format!("cannot write the model to {}: {e}", out.dir.display());
        match e.kind() {
            K::DirectoryNotEmpty
            | K::AlreadyExists
            | K::NotADirectory
            | K::NotFound
            | K::InvalidInput => Failure::input(message),
            _ => Failure::solver(message),
        }
    })
}

fn written_line(w: &Written, total: usize) -> String {
    let mut s = format!(
        "Wrote {} ({} format): {} of {total} image poses replaced by the re-estimated ones.",
        w.dir.display(),
        format_name(w.format),
        w.replaced
    );
    if !w.kept.is_empty() {
        let ids: Vec<String> = w.kept.iter().map(u32::to_string).collect();
        let _ = write!(
            s,
            " Not registered, keeping the input model's pose: image{} {}.",
            if ids.len() == 1 { "" } else { "s" },
            ids.join(", ")
        );
    }
    s.push('\n');
    s
}

/// `--export-problems FILE` must not resolve into the input model's directory (it could
/// replace one of the model's own files).
fn check_export(input: &Path, file: &Path) -> Result<(), Failure> {
    let bad = |why: &str| {
        Failure::input(format!(
            "--export-problems {}: {why}",
            super::escaped(&file.display().to_string())
        ))
    };
    let input_c = std::fs::canonicalize(input).map_err(|e| bad(&e.to_string()))?;
    let Some(name) = file.file_name() else {
        return Err(bad("not a file name"));
    };
    let parent = match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let parent_c =
        std::fs::canonicalize(parent).map_err(|_| bad("its parent directory does not exist"))?;
    let target = parent_c.join(name);
    // A symbolic link at the target is followed, as the write would follow it.
    let target = std::fs::canonicalize(&target).unwrap_or(target);
    if target.starts_with(&input_c) {
        return Err(bad(
            "is inside the input model's directory (refusing to write over the input)",
        ));
    }
    Ok(())
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename: a
/// failure leaves no partial file and the previous content of `path`, if any, unchanged.
fn write_file_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "no file name"))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

pub(crate) fn run(
    dir: &Path,
    opts: &RegisterOptions,
    out: Option<&Output>,
    intro: bool,
) -> Result<(), Failure> {
    let format = colmap::detect_format(dir).map_err(|e| {
        let hint = if intro {
            "\n(the bundled model is missing; run `eopnp register MODEL_DIR` on a COLMAP model)"
        } else {
            ""
        };
        Failure::input(format!("{e}{hint}"))
    })?;
    opts.validate()?;
    let limits = opts
        .max_input_size
        .map_or_else(colmap::ReadOptions::default, |n| {
            colmap::ReadOptions::default().max_file_bytes(n)
        });
    let model = colmap::read_model(dir, &limits).map_err(|e| {
        let hint = if matches!(e.kind, ModelErrorKind::Limit(Limit::FileBytes(_))) {
            "; raise it with --max-input-size SIZE"
        } else {
            ""
        };
        Failure::input(format!("{e}{hint}"))
    })?;
    if let Some(out) = out {
        check_output(dir, &out.dir)?;
    }
    let mode = match (opts.algebraic, opts.ransac) {
        (true, false) => "algebraic",
        (false, false) => "reprojection",
        (true, true) => "ransac+algebraic",
        (false, true) => "ransac+reprojection",
    };
    // Frames of several images are registered as rig poses; a model whose frames each hold one
    // image (what COLMAP 3.12 and later write for a model without rigs) image by image.
    let multi_image_frames = model.frames.values().any(|f| f.image_ids().count() > 1);
    if multi_image_frames && !opts.per_image && opts.unknown_focal {
        return Err(Failure::input(
            "--unknown-focal estimates one camera's focal length image by image; a rig pose \
             with unknown focal lengths is not supported: on a model whose frames hold several \
             images, add --per-image",
        ));
    }
    if multi_image_frames && !opts.per_image {
        if opts.outliers.is_some() || opts.export_problems.is_some() {
            return Err(Failure::input(
                "--outliers and --export-problems work image by image: on a model whose \
                 frames hold several images, add --per-image",
            ));
        }
        return frames::run(dir, format, &model, opts, mode, out);
    }
    if multi_image_frames && out.is_some() {
        return Err(Failure::input(
            "--per-image with --write on a model whose frames hold several images would leave \
             the frames' poses inconsistent with their images' (COLMAP derives the images' \
             poses from the frames'): write without --per-image",
        ));
    }
    if let Some(path) = &opts.export_problems {
        check_export(dir, path)?;
        write_file_atomically(path, export_problems(&model, opts).as_bytes())
            .map_err(|e| Failure::input(format!("cannot write {}: {e}", path.display())))?;
    }

    let bar = progress_bar(model.images.len() as u64, "images");
    let started = Instant::now();
    let mut rows: Vec<Row> = Vec::with_capacity(model.images.len());
    let mut registrar = Registrar::new(&model);
    for (id, img) in &model.images {
        if started.elapsed() >= PROGRESS_AFTER && std::io::stderr().is_terminal() {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        let (result, extra) = estimate(&mut registrar, &model, *id, opts);
        rows.push((*id, img.name.clone(), result, extra));
        bar.inc(1);
    }
    bar.finish_and_clear();

    let written = out
        .map(|o| write_output(&model, format, &rows, o))
        .transpose()?;
    let text = if opts.json {
        to_json(dir, format, mode, &rows, written.as_ref())
    } else {
        let mut t = to_table(dir, format, mode, &rows, &model, intro);
        if let Some(w) = &written {
            t.push_str(&written_line(w, rows.len()));
        }
        t
    };
    emit(&text)?;
    if rows.iter().all(|r| r.2.is_err()) && !rows.is_empty() {
        return Err(Failure::solver("no image could be registered"));
    }
    Ok(())
}

/// The progress bar of registering `len` images or frames (`what`), hidden until shown.
fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
    let template = format!("{{spinner}} registering {what} {{pos}}/{{len}} [{{bar:30}}] {{eta}}");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
