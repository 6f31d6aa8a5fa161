//! The command line of `eopnp-compare`.

use std::path::PathBuf;
use std::time::Duration;

/// Default seed of the comparison (independent of the test suite's seed).
const DEFAULT_SEED: u64 = 0x0E0F_C0DE_2019;

#[derive(Clone, Debug)]
pub struct Args {
    pub trials: usize,
    pub passes: usize,
    pub seed: u64,
    pub out: PathBuf,
    pub kornia_timeout: Duration,
    pub json: bool,
    /// `--runs K`: repeat the measurement K times and print the speed summary.
    pub runs: Option<usize>,
    /// Child mode: run the guarded kornia-pnp pass of this row and print the outcomes.
    pub kornia_row: Option<usize>,
}

pub fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        trials: 500,
        passes: 5,
        seed: DEFAULT_SEED,
        out: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/compare"),
        kornia_timeout: Duration::from_millis(200),
        json: true,
        runs: None,
        kornia_row: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--trials" => a.trials = value()?.parse().map_err(|e| format!("--trials: {e}"))?,
            "--passes" => a.passes = value()?.parse().map_err(|e| format!("--passes: {e}"))?,
            "--seed" => {
                let v = value()?;
                a.seed = match v.strip_prefix("0x") {
                    Some(h) => u64::from_str_radix(h, 16),
                    None => v.parse(),
                }
                .map_err(|e| format!("--seed: {e}"))?;
            }
            "--out" => a.out = PathBuf::from(value()?),
            "--kornia-timeout-ms" => {
                a.kornia_timeout = Duration::from_millis(
                    value()?
                        .parse()
                        .map_err(|e| format!("--kornia-timeout-ms: {e}"))?,
                )
            }
            "--no-json" => a.json = false,
            "--runs" => a.runs = Some(value()?.parse().map_err(|e| format!("--runs: {e}"))?),
            "--kornia-row" => {
                a.kornia_row = Some(value()?.parse().map_err(|e| format!("--kornia-row: {e}"))?)
            }
            "-h" | "--help" => {
                println!(
                    "eopnp-compare [--trials N=500] [--passes P=5] [--seed S] [--out DIR] \
                     [--kornia-timeout-ms MS=200] [--no-json] [--runs K]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if a.trials == 0 || a.passes == 0 || a.runs == Some(0) {
        return Err("--trials, --passes and --runs must be positive".into());
    }
    Ok(a)
}
