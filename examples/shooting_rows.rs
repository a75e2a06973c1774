//! The violated rows of a shooting point read from a solution file:
//! `cargo run --release --example shooting_rows -- MODEL SOLUTION.sto N`.
use leap::nlp::Nlp;
use std::sync::Arc;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (model, file, n) = (&a[1], &a[2], a[3].parse::<usize>().expect("N"));
    let model = leap::model::Model::from_file(std::path::Path::new(model)).expect("model");
    let opts = leap::ocp::OcpOptions {
        no_countermovement_nodes: 7.min(n),
        ..Default::default()
    };
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, opts).expect("ocp"));
    let mut sh = leap::shooting::Shooting::new(
        ocp.clone(),
        leap::shooting::ShootingOptions {
            num_intervals: n,
            ..Default::default()
        },
    )
    .expect("shooting");
    let eq = &ocp.eq;
    let muscles: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&m| eq.model.muscles[m].spec.name.as_str())
        .collect();
    let c = leap::io::Controls::from_file(std::path::Path::new(file), &muscles).expect("controls");
    let tf = *c.time.last().expect("time");
    let v = sh.point_from_source(&c, tf).expect("point");
    let m = sh.num_constraints();
    let (mut lo, mut hi) = (vec![0.0; m], vec![0.0; m]);
    sh.constraint_bounds(&mut lo, &mut hi);
    let mut cv = vec![0.0; m];
    sh.constraints(&v, &mut cv).expect("constraints");
    for i in 0..m {
        let viol = (lo[i] - cv[i]).max(cv[i] - hi[i]);
        if viol > 1e-6 {
            println!(
                "{}: {} not in [{}, {}]",
                sh.constraint_name(i),
                cv[i],
                lo[i],
                hi[i]
            );
        }
    }
    println!("J {}", -sh.objective(&v).expect("objective"));
}
