//! `eopnp`: camera pose from 2D-3D correspondences on the command line.
//!
//! - `eopnp` (no arguments): `register` on the COLMAP reconstruction bundled with the
//!   repository (`data/colmap-boxes`), with an explanation of the output.
//! - `eopnp register MODEL_DIR [--json] [--algebraic]`: re-estimates every image's pose of a
//!   COLMAP model (text or binary) and compares it with the model's.
//! - `eopnp solve FILE|- [--format csv|json] [--camera "MODEL P1 P2 ..."]`: correspondences
//!   (CSV or JSON, a file or standard input) in, pose JSON out.
//!
//! Exit codes: 0 success, 1 the solver failed on valid input, 2 bad input (unreadable or
//! malformed file, with the line number and the reason; bad arguments).

use eopnp_cli as cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
