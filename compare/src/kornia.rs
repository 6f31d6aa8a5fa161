//! kornia-pnp's guarded accuracy pass: one watchdog thread per call, in a child process
//! (`--kornia-row`) so that the threads of hung calls die with it.

use crate::args::Args;
use crate::peers::{self, Pose};
use crate::rows::{generate, rows};
use crate::KORNIA_MAX_HANGS_PER_ROW;
use std::fmt::Write as _;
use std::io::Write as _;

/// Outcome of one guarded kornia-pnp call.
#[derive(Clone, Copy, Debug)]
pub enum KorniaOutcome {
    Returned(Option<Pose>),
    Panicked,
    TimedOut,
    Skipped,
}

/// The guarded accuracy pass over a row's inputs (in this process): one watchdog thread per
/// call; after [`KORNIA_MAX_HANGS_PER_ROW`] hangs the rest of the row is skipped.
pub fn kornia_accuracy(inputs: &[peers::KorniaInput], args: &Args) -> Vec<KorniaOutcome> {
    let mut hangs = 0;
    inputs
        .iter()
        .map(|q| {
            if hangs >= KORNIA_MAX_HANGS_PER_ROW {
                return KorniaOutcome::Skipped;
            }
            match peers::kornia_guarded(q, args.kornia_timeout) {
                peers::Guarded::Returned(r) => KorniaOutcome::Returned(r),
                peers::Guarded::Panicked => KorniaOutcome::Panicked,
                peers::Guarded::TimedOut => {
                    hangs += 1;
                    KorniaOutcome::TimedOut
                }
            }
        })
        .collect()
}

/// Child mode (`--kornia-row I`): the guarded pass of row `I`, one line per trial on stdout
/// (`ok` + 12 numbers, `none`, `panic`, `timeout`, `skipped`); then exit, which also ends the
/// threads of hung calls.
pub fn kornia_child_main(i: usize, args: &Args) -> ! {
    let rows = rows();
    let Some(row) = rows.get(i) else {
        std::process::exit(2)
    };
    let inputs: Vec<_> = generate(row, args)
        .iter()
        .map(peers::kornia_input)
        .collect();
    let mut out = String::new();
    for o in kornia_accuracy(&inputs, args) {
        match o {
            KorniaOutcome::Returned(Some((r, t))) => {
                let _ = write!(out, "ok");
                for x in r.iter().chain(t.iter()) {
                    let _ = write!(out, " {x:?}");
                }
                out.push('\n');
            }
            KorniaOutcome::Returned(None) => out.push_str("none\n"),
            KorniaOutcome::Panicked => out.push_str("panic\n"),
            KorniaOutcome::TimedOut => out.push_str("timeout\n"),
            KorniaOutcome::Skipped => out.push_str("skipped\n"),
        }
    }
    let mut so = std::io::stdout().lock();
    let _ = so.write_all(out.as_bytes());
    let _ = so.flush();
    std::process::exit(0)
}

/// Runs the child for row `i` and parses its outcomes; `None` if it could not be run.
pub fn kornia_child(i: usize, args: &Args) -> Option<Vec<KorniaOutcome>> {
    let exe = std::env::current_exe().ok()?;
    let out = std::process::Command::new(exe)
        .args([
            "--kornia-row".to_string(),
            i.to_string(),
            "--trials".into(),
            args.trials.to_string(),
            "--seed".into(),
            args.seed.to_string(),
            "--kornia-timeout-ms".into(),
            args.kornia_timeout.as_millis().to_string(),
        ])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    text.lines()
        .map(|l| {
            let mut w = l.split_whitespace();
            Some(match w.next()? {
                "ok" => {
                    let v: Vec<f64> = w.map(|x| x.parse().ok()).collect::<Option<_>>()?;
                    if v.len() != 12 {
                        return None;
                    }
                    KorniaOutcome::Returned(Some((
                        nalgebra::Matrix3::from_column_slice(&v[..9]),
                        nalgebra::Vector3::new(v[9], v[10], v[11]),
                    )))
                }
                "none" => KorniaOutcome::Returned(None),
                "panic" => KorniaOutcome::Panicked,
                "timeout" => KorniaOutcome::TimedOut,
                "skipped" => KorniaOutcome::Skipped,
                _ => return None,
            })
        })
        .collect()
}
