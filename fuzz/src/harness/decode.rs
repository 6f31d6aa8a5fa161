//! The shared decoder: a byte reader that never runs out, and the problem and solver
//! configuration every `solve`-family input decodes to.

use eopnp::{Loss, PlanarDetection, Refinement, Solver};
use nalgebra::{Matrix3, Point2, Point3, Rotation3, Vector3};

/// Largest N the decoder builds (N up to 10,000).
pub const MAX_POINTS: usize = 10_000;

/// A little-endian byte reader that yields zeros once the input is exhausted, so every input
/// decodes to something.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

/// Values that break naive numerics, picked by one byte.
const SPECIAL: [f64; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e300,
    -1e300,
    1e-300,
    5e-324, // smallest subnormal
    f64::MAX,
    f64::MIN_POSITIVE,
    1e-8,
    1e8,
    0.5,
];

impl<'a> Reader<'a> {
    /// A reader over `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, pos: 0 }
    }

    /// The next byte (0 when exhausted).
    pub fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    /// The next `n` bytes, zero-padded.
    fn bytes<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0; N];
        for b in &mut out {
            *b = self.u8();
        }
        out
    }

    /// A number: the tag byte's top three bits pick the encoding, so that small integers and
    /// quarters, special values, raw `f64`/`f32` bit patterns and wide-range magnitudes are
    /// all one mutation away from each other.
    pub fn f64(&mut self) -> f64 {
        let tag = self.u8();
        let low = f64::from(tag & 31);
        match tag >> 5 {
            0..=2 => (low - 16.0) / 4.0,
            3 => SPECIAL[usize::from(tag & 15)],
            4 => f64::from_le_bytes(self.bytes::<8>()),
            5 => f64::from(i16::from_le_bytes(self.bytes::<2>())) / 256.0,
            6 => (f64::from(self.u8()) - 128.0) / 16.0 * 10f64.powi(i32::from(tag & 31) - 16),
            _ => f64::from(f32::from_le_bytes(self.bytes::<4>())),
        }
    }

    /// Whether the input is exhausted.
    pub fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
}

/// A decoded PnP problem.
pub struct Problem {
    /// World points.
    pub world: Vec<Point3<f64>>,
    /// Normalised image points (one more or one fewer than `world` when lengths are fuzzed).
    pub image: Vec<Point2<f64>>,
    /// Per-point weights (`None`: unweighted).
    pub weights: Option<Vec<f64>>,
    /// The generating pose when the image points are its exact projections (no noise, no
    /// length change): a pose with zero reprojection error exists.
    pub exact_pose: Option<(Matrix3<f64>, Vector3<f64>)>,
}

/// Decodes a problem. Layout: a flags byte, a base count, a tiling count, then the base points
/// (and, when the flags say so, a pose that projects them, with per-point noise), then the tiling
/// offset. Tiling repeats the base set shifted by multiples of the offset up to
/// [`MAX_POINTS`], so that large N costs few input bytes.
pub fn decode_problem(r: &mut Reader) -> Problem {
    let flags = r.u8();
    let project = flags & 1 != 0;
    let weighted = flags & 2 != 0;
    let length_fuzz = flags & 4 != 0;
    let tile = flags & 8 != 0;
    let base = usize::from(r.u8() % 48);
    let reps = if tile {
        1 + usize::from(u16::from_le_bytes([r.u8(), r.u8()])) % MAX_POINTS
    } else {
        1
    };
    let mut world0 = Vec::with_capacity(base);
    for _ in 0..base {
        world0.push(Point3::new(r.f64(), r.f64(), r.f64()));
    }
    let mut image0 = Vec::with_capacity(base);
    let pose = if project {
        // Rotation from a (possibly huge or non-finite) rotation vector, translation as given.
        let rv = Vector3::new(r.f64(), r.f64(), r.f64());
        let t = Vector3::new(r.f64(), r.f64(), r.f64());
        let rot = if rv.iter().all(|x| x.is_finite()) && rv.norm().is_finite() {
            Rotation3::new(rv).into_inner()
        } else {
            Matrix3::identity()
        };
        Some((rot, t))
    } else {
        None
    };
    let mut noiseless = true;
    for x in &world0 {
        let p = match &pose {
            Some((rot, t)) => {
                let c = rot * x.coords + t;
                let noise = (r.f64(), r.f64());
                noiseless &= noise == (0.0, 0.0);
                let scale = 1e-3;
                Point2::new(c.x / c.z + scale * noise.0, c.y / c.z + scale * noise.1)
            }
            None => Point2::new(r.f64(), r.f64()),
        };
        image0.push(p);
    }
    let offset = Vector3::new(r.f64(), r.f64(), r.f64());
    let n = (base * reps).min(MAX_POINTS);
    let mut world = Vec::with_capacity(n);
    let mut image = Vec::with_capacity(n);
    for k in 0..n {
        let (i, rep) = (k % base.max(1), (k / base.max(1)) as f64);
        let x = world0[i] + rep * offset;
        let p = match &pose {
            Some((rot, t)) if rep > 0.0 => {
                let c = rot * x.coords + t;
                Point2::new(c.x / c.z, c.y / c.z)
            }
            _ => image0[i],
        };
        world.push(x);
        image.push(p);
    }
    let exact_pose = pose.filter(|_| noiseless && !length_fuzz);
    if length_fuzz {
        match r.u8() % 3 {
            0 => {
                image.pop();
            }
            1 => image.push(Point2::new(0.0, 0.0)),
            _ => {
                world.pop();
            }
        }
    }
    let weights = weighted.then(|| {
        let w: Vec<f64> = (0..base).map(|_| r.f64()).collect();
        let mut out: Vec<f64> = (0..world.len())
            .map(|k| if base == 0 { 1.0 } else { w[k % base] })
            .collect();
        if length_fuzz && r.u8() & 1 != 0 {
            out.pop();
        }
        out
    });
    Problem {
        world,
        image,
        weights,
        exact_pose,
    }
}

/// A solver configuration from one byte.
pub fn decode_solver(b: u8) -> Solver {
    let mut s = Solver::default();
    if b & 1 != 0 {
        s = s.refinement(Refinement::Algebraic);
    }
    if b & 2 != 0 {
        s = s.exhaustive(true);
    }
    s = s.planar_detection(match (b >> 2) & 3 {
        1 => PlanarDetection::Planar,
        2 => PlanarDetection::NonPlanar,
        _ => PlanarDetection::Auto,
    });
    if b & 16 != 0 {
        // Tiny iteration budgets: the hard bounds must be honoured without a wrong Ok.
        s = s
            .newton_iterations(u32::from(b >> 5))
            .reprojection_iterations(u32::from(b >> 5));
    } else {
        // A robust loss for the final refinement (`refine_pixels`), at a small or a large scale.
        let scale = if b & 128 != 0 { 1e-2 } else { 1e-4 };
        s = s.loss(match (b >> 5) & 3 {
            1 => Loss::Huber(scale),
            2 => Loss::Cauchy(scale),
            _ => Loss::Squared,
        });
    }
    s
}
