//! Re-solve a QP that the SQP wrote with `qp_dump_dir` (clarabel JSON):
//! `cargo run --release --example qp_replay -- qp_iter12_failed.json`.
use clarabel::solver::*;
fn main() {
    let mut f = std::fs::File::open(std::env::args().nth(1).unwrap()).unwrap();
    let mut s = DefaultSolver::<f64>::load_from_file(&mut f, None).unwrap();
    s.solve();
    println!("{:?} x {:?} z {:?}", s.solution.status, s.solution.x, s.solution.z);
}
