//! The rows of the protocol and their problems (generated, and written as JSON).

use crate::args::Args;
use crate::common::{self, Problem, ProblemOptions, RotationKind, Scene};
use crate::FAIL_DEG;
use std::io::Write as _;

/// One row of the protocol.
#[derive(Clone, Debug)]
pub struct Row {
    pub group: usize,
    pub label: String,
    pub scene: Scene,
    pub n: usize,
    pub sigma: f64,
}

pub const GROUPS: [&str; 4] = [
    "General scene, N sweep (sigma = 2 px)",
    "General scene, sigma sweep (N = 10)",
    "Planar scene (random tilt), sigma = 2 px",
    "Quasi-singular scene, sigma = 2 px",
];

pub fn rows() -> Vec<Row> {
    let mut v = Vec::new();
    let row = |group, scene, n, sigma: f64| Row {
        group,
        label: format!("N = {n}, sigma = {sigma} px"),
        scene,
        n,
        sigma,
    };
    for n in [4, 5, 6, 8, 10, 15, 20, 50, 100, 1000] {
        v.push(row(0, Scene::General, n, 2.0));
    }
    for s in [0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0] {
        v.push(row(1, Scene::General, 10, s));
    }
    for n in [4, 6, 10, 100] {
        v.push(row(2, Scene::Planar, n, 2.0));
    }
    for n in [6, 10, 100] {
        v.push(row(3, Scene::QuasiSingular, n, 2.0));
    }
    v
}

fn scene_name(s: Scene) -> &'static str {
    match s {
        Scene::General => "general",
        Scene::Planar => "planar",
        Scene::QuasiSingular => "quasi_singular",
    }
}

/// The problems of a row: trial `i` from `splitmix(seed ^ hash(row) ^ splitmix(i))`.
pub fn generate(row: &Row, args: &Args) -> Vec<Problem> {
    let name = format!("compare/{}/{}/{}", scene_name(row.scene), row.n, row.sigma);
    let h = common::name_hash(&name);
    (0..args.trials as u64)
        .map(|i| {
            Problem::generate(&ProblemOptions {
                n: row.n,
                sigma_px: row.sigma,
                scene: row.scene,
                rotation: RotationKind::Uniform,
                seed: common::splitmix64(args.seed ^ common::splitmix64(h ^ common::splitmix64(i))),
            })
        })
        .collect()
}

/// Writes every problem as JSON (numbers in Rust's shortest round-trip form).
pub fn write_problems(
    path: &std::path::Path,
    args: &Args,
    all: &[(Row, Vec<Problem>)],
) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let v3 = |x: f64, y: f64, z: f64| format!("[{x:?},{y:?},{z:?}]");
    writeln!(
        w,
        "{{\"format\":\"eopnp-compare problems v1\",\"seed\":{},\"fail_deg\":{:?},\
         \"intrinsics\":{{\"fx\":{:?},\"fy\":{:?},\"cx\":{:?},\"cy\":{:?}}},\
         \"conventions\":\"x_cam = R X + t; pixels = f (x/z, y/z) + (cx, cy) + noise; image = \
         (pixels - (cx, cy)) / f; R row-major\",\"rows\":[",
        args.seed,
        FAIL_DEG,
        common::F,
        common::F,
        common::CX,
        common::CY
    )?;
    for (ri, (row, probs)) in all.iter().enumerate() {
        write!(
            w,
            "{}{{\"group\":{:?},\"label\":{:?},\"scene\":\"{}\",\"n\":{},\"sigma_px\":{:?},\"problems\":[",
            if ri > 0 { ",\n" } else { "" },
            GROUPS[row.group],
            row.label,
            scene_name(row.scene),
            row.n,
            row.sigma
        )?;
        for (pi, p) in probs.iter().enumerate() {
            let world: Vec<String> = p.world.iter().map(|x| v3(x.x, x.y, x.z)).collect();
            let pix: Vec<String> = p
                .pixels
                .iter()
                .map(|m| format!("[{:?},{:?}]", m.x, m.y))
                .collect();
            let img: Vec<String> = p
                .image
                .iter()
                .map(|m| format!("[{:?},{:?}]", m.x, m.y))
                .collect();
            let r = &p.r_gt;
            write!(
                w,
                "{}{{\"seed\":{},\"world\":[{}],\"pixels\":[{}],\"image\":[{}],\"r_gt\":[{},{},{}],\"t_gt\":{}}}",
                if pi > 0 { ",\n" } else { "\n" },
                p.opts.seed,
                world.join(","),
                pix.join(","),
                img.join(","),
                v3(r[(0, 0)], r[(0, 1)], r[(0, 2)]),
                v3(r[(1, 0)], r[(1, 1)], r[(1, 2)]),
                v3(r[(2, 0)], r[(2, 1)], r[(2, 2)]),
                v3(p.t_gt.x, p.t_gt.y, p.t_gt.z)
            )?;
        }
        write!(w, "]}}")?;
    }
    writeln!(w, "]}}")?;
    w.flush()
}
