//! Decodes a `solve`/`ransac` fuzz input and prints the problem and the solver's answers:
//! `cargo run --manifest-path fuzz/Cargo.toml --example show -- solve FILE`.
use eopnp::Problem;
use eopnp_fuzz::{decode_problem, decode_solver, Reader};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let data = std::fs::read(&args[2]).expect("read input");
    let mut r = Reader::new(&data);
    let solver_byte = r.u8();
    if args[1] == "ransac" {
        let v: Vec<f64> = (0..4).map(|_| r.f64()).collect();
        println!(
            "threshold {} confidence {} focal ({}, {})",
            v[0], v[1], v[2], v[3]
        );
        println!(
            "seed {} max_iter/4 {} lo {} min_iter {}",
            r.u8(),
            r.u8(),
            r.u8(),
            r.u8()
        );
        println!("factor {}", r.f64());
    }
    let solver = decode_solver(solver_byte);
    println!("solver byte {solver_byte:#x}: {solver:?}");
    let p = decode_problem(&mut r);
    println!(
        "N = {} / {}, weights {:?}",
        p.world.len(),
        p.image.len(),
        p.weights
    );
    for (k, (x, u)) in p.world.iter().zip(&p.image).enumerate().take(50) {
        println!(
            "{k:3}: world [{:e}, {:e}, {:e}]  image [{:e}, {:e}]",
            x.x, x.y, x.z, u.x, u.y
        );
    }
    println!(
        "solve: {:#?}",
        solver.solve(&Problem::normalised(&p.world, &p.image))
    );
    if let Ok(all) = solver.solve_all(&Problem::normalised(&p.world, &p.image)) {
        for s in &all {
            println!(
                "solve_all: cost {:e} alg {:e} rmse {:e} source {:?}",
                s.cost, s.algebraic_cost, s.reprojection_rmse, s.source
            );
        }
    }
}
