//! Measurements of one check over many samples, and the Markdown report table.

use std::fmt::Write as _;

/// The outcome of one check over its samples.
#[derive(Clone, Debug)]
pub struct Measurement {
    /// Kernel name (as in `eopnp::internals::kernels::ALL_KERNEL_OPS`).
    pub kernel: &'static str,
    /// What the kernel is compared with.
    pub check: &'static str,
    /// The error norm, in words.
    pub norm: &'static str,
    /// The asserted bound, in words (a number, or "derived per sample").
    pub bound: String,
    /// Number of samples.
    pub samples: usize,
    /// Worst error in `norm`.
    pub worst: f64,
    /// Worst `error / bound` over the samples (the check passes iff this is `<= 1`).
    pub worst_ratio: f64,
    /// The input that produced `worst_ratio` (seed, sample index, values).
    pub worst_input: String,
}

/// Accumulates per-sample errors into a [`Measurement`].
#[derive(Debug)]
pub struct Tracker {
    m: Measurement,
}

impl Tracker {
    /// Start a check.
    #[must_use]
    pub fn new(
        kernel: &'static str,
        check: &'static str,
        norm: &'static str,
        bound: String,
    ) -> Self {
        Self {
            m: Measurement {
                kernel,
                check,
                norm,
                bound,
                samples: 0,
                worst: 0.0,
                worst_ratio: 0.0,
                worst_input: String::new(),
            },
        }
    }

    /// Record one sample: its error in the norm and the bound it must meet. A NaN error
    /// counts as an infinite ratio.
    pub fn record(&mut self, err: f64, bound: f64, input: impl FnOnce() -> String) {
        self.m.samples += 1;
        let ratio = if err.is_nan() || bound.is_nan() {
            f64::INFINITY
        } else if err == 0.0 {
            0.0
        } else {
            err / bound
        };
        if err > self.m.worst || err.is_nan() {
            self.m.worst = if err.is_nan() { f64::INFINITY } else { err };
        }
        if ratio > self.m.worst_ratio || self.m.samples == 1 {
            self.m.worst_ratio = ratio;
            self.m.worst_input = input();
        }
    }

    /// Record one sample whose `error / bound` ratio is computed by the caller (a bound that is
    /// a maximum of several, or not a number in the reported norm). Unlike [`Tracker::record`],
    /// an error of exactly 0 does not set the ratio to 0: the caller's ratio is kept. A NaN
    /// ratio counts as infinite.
    pub fn record_ratio(&mut self, err: f64, ratio: f64, input: impl FnOnce() -> String) {
        self.m.samples += 1;
        let ratio = if ratio.is_nan() || err.is_nan() {
            f64::INFINITY
        } else {
            ratio
        };
        if err > self.m.worst || err.is_nan() {
            self.m.worst = if err.is_nan() { f64::INFINITY } else { err };
        }
        if ratio > self.m.worst_ratio || self.m.samples == 1 {
            self.m.worst_ratio = ratio;
            self.m.worst_input = input();
        }
    }

    /// The measurement.
    #[must_use]
    pub fn finish(self) -> Measurement {
        self.m
    }
}

impl Measurement {
    /// Whether every sample met its bound.
    #[must_use]
    pub fn passed(&self) -> bool {
        self.worst_ratio <= 1.0 && self.samples > 0
    }

    /// Panic with the details unless [`Measurement::passed`].
    pub fn assert_ok(&self) {
        assert!(
            self.passed(),
            "{} ({}): worst error {:.3e} ({}), bound {}, worst error/bound {:.3e} at {}",
            self.kernel,
            self.check,
            self.worst,
            self.norm,
            self.bound,
            self.worst_ratio,
            self.worst_input
        );
    }
}

/// The Markdown table: kernel | check | samples | worst error (norm) | bound | worst/bound |
/// ops after CSE | naive ops (terms), with the op counts from `eopnp::internals::kernels::ALL_KERNEL_OPS`.
#[must_use]
pub fn table(ms: &[Measurement]) -> String {
    let mut out = String::new();
    out.push_str(
        "| kernel | check | samples | worst error (norm) | bound | worst/bound | ops after CSE | naive ops (terms) |\n",
    );
    out.push_str("|---|---|---|---|---|---|---|---|\n");
    for m in ms {
        let ops = eopnp::internals::kernels::ALL_KERNEL_OPS
            .iter()
            .find(|o| o.name == m.kernel);
        let (cse, naive) = match ops {
            Some(o) => (
                format!("{} mul + {} add", o.mul, o.add),
                format!(
                    "{} mul + {} add ({} terms)",
                    o.naive_mul, o.naive_add, o.naive_terms
                ),
            ),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.2e} ({}) | {} | {:.2e}{} | {} | {} |",
            m.kernel,
            m.check,
            m.samples,
            m.worst,
            m.norm.replace('|', "\\|"), // a literal | would end the Markdown cell
            m.bound,
            m.worst_ratio,
            if m.passed() { "" } else { " FAIL" },
            cse,
            naive
        );
    }
    out
}
