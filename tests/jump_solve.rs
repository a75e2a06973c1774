//! The jump solved end to end (issue 5, point 9). CI solves a reduced
//! instance: the same problem and transcription on the 10-muscle-per-side
//! `models/jumper_reduced.json` (`models/jump_reduced.json`). The full
//! problem, `leap solve`'s default study, is an ignored test that
//! `scripts/full_solve.sh` runs; it asserts issue 5's "done when".

use leap::solve::SolveReport;
use leap::sqp::SqpStatus;
use leap::study::{Overrides, SolveConfig};
use std::path::Path;

fn solve(study: &str, tag: &str) -> SolveReport {
    solve_with(study, tag, Overrides::default())
}

fn solve_with(study: &str, tag: &str, overrides: Overrides) -> SolveReport {
    let out = std::env::temp_dir().join(format!("leap_jump_solve_{}_{tag}", std::process::id()));
    let mut config = SolveConfig::load(Some(Path::new(study))).unwrap();
    config
        .apply(&Overrides {
            output_directory: Some(out.clone()),
            ..overrides
        })
        .unwrap();
    let verbose = std::env::var_os("LEAP_SQP_VERBOSE").is_some();
    let report = leap::solve::run(&config, verbose, &mut |_| {}).unwrap();
    eprintln!(
        "{study} ({:?}, {} fibre dynamics, {} backend): {:?} after {} iterations, {:.1} s; jump {:.2} cm, forward check {:+.2} cm, violation {:.1e}",
        report.method,
        report.fiber_dynamics,
        report.backend,
        report.status,
        report.iterations,
        report.wall_time_s,
        100.0 * report.jump_height_m,
        100.0 * report.forward_check_difference_m.unwrap_or(f64::NAN),
        report.max_constraint_violation
    );
    let _ = std::fs::remove_dir_all(&out);
    report
}

/// The paper's 29 nodes on the reduced model: solved, the constraints
/// within the paper's 1e-3, and the optimal excitations, integrated by
/// Simbody's variable-step integrator with OpenSim's own activation
/// switch, jumping as high as predicted within issue 5's 1 cm.
#[test]
fn reduced_jump_is_solved_and_agrees_with_its_forward_simulation() {
    assert_solved_and_forward_checked(&solve_reduced("explicit"));
}

/// The same with implicit fibre dynamics (the force balance in place of the
/// inverted force–velocity curve): the same problem, so the same checks.
#[test]
fn reduced_jump_with_implicit_fibre_dynamics_is_solved_and_agrees() {
    assert_solved_and_forward_checked(reduced_implicit());
}

/// The reduced study's solve with implicit fibre dynamics (its default),
/// once for the tests that need it.
fn reduced_implicit() -> &'static SolveReport {
    static R: std::sync::OnceLock<SolveReport> = std::sync::OnceLock::new();
    R.get_or_init(|| solve_reduced("implicit"))
}

/// The cross-check path (`--backend simbody`): every point of the
/// transcription evaluated by Simbody's multibody system, the Jacobian by
/// coloured central differences. Solved and forward-checked as the
/// Rust-native solves are, and predicting the jump of the Rust-native
/// solve within issue 5's 1 cm (measured 0.001 cm: the two dynamics agree
/// to 1e-9 and the Jacobians to 1e-6, `transcription::simbody_backend_*`).
#[test]
fn reduced_jump_through_simbody_agrees_with_rust_native() {
    let r = solve_with(
        "models/jump_reduced.json",
        "reduced_simbody",
        Overrides {
            backend: Some("simbody".into()),
            ..Default::default()
        },
    );
    assert_eq!(r.backend, "simbody");
    assert_solved_and_forward_checked(&r);
    let native = reduced_implicit();
    assert_eq!(
        (native.backend, native.fiber_dynamics),
        ("rust-native", r.fiber_dynamics)
    );
    let gap = r.jump_height_m - native.jump_height_m;
    eprintln!(
        "Simbody backend {:.4} cm, Rust-native {:.4} cm",
        100.0 * r.jump_height_m,
        100.0 * native.jump_height_m
    );
    assert!(gap.abs() <= 0.01, "the backends' jumps differ by {gap} m");
}

/// Hermite–Simpson on the reduced jump (its default eigenvalue floor and
/// the fibre clamp spread over a band): solved, and the optimal excitations
/// jump forward as predicted within 1 cm.
#[test]
fn reduced_jump_by_hermite_simpson_is_solved_and_agrees() {
    assert_solved_and_forward_checked(&solve_by_hermite_simpson(
        "models/jump_reduced.json",
        "reduced_hs",
    ));
}

/// A study solved by Hermite–Simpson (`--scheme hermite-simpson`).
fn solve_by_hermite_simpson(study: &str, tag: &str) -> SolveReport {
    solve_with(
        study,
        tag,
        Overrides {
            scheme: Some("hermite-simpson".into()),
            ..Default::default()
        },
    )
}

/// The reduced study with the given fibre dynamics.
fn solve_reduced(fiber: &str) -> SolveReport {
    let r = solve_with(
        "models/jump_reduced.json",
        &format!("reduced_{fiber}"),
        Overrides {
            fiber_dynamics: Some(fiber.into()),
            ..Default::default()
        },
    );
    assert_eq!(r.fiber_dynamics, fiber);
    r
}

/// Solved within the paper's 1e-3, a jump, and the forward simulation of
/// its excitations within 1 cm and one mesh interval of it.
fn assert_solved_and_forward_checked(r: &SolveReport) {
    assert_eq!(r.status, SqpStatus::Solved, "{}", r.message);
    assert!(r.max_constraint_violation <= 1e-3);
    let diff = r.forward_check_difference_m.expect("forward check ran");
    assert!(diff.abs() <= 0.01, "forward check differs by {diff} m");
    // A jump, not a stumble: lift-off upwards after a push-off.
    assert!(r.lifted_off);
    assert!(r.liftoff_com_velocity_mps > 0.5 && r.ground_contact_time_s > 0.1);
    // The predicted lift-off (where the ground force at the midpoints
    // falls through 1% of body weight, t_f possibly later) within one mesh
    // interval of the forward simulation's.
    let forward = r.forward_check.as_ref().unwrap().summary.as_ref().unwrap();
    let forward_liftoff = forward.liftoff_time_s.expect("the forward jump lifts off");
    let h = r.final_time_s / r.num_mesh_intervals as f64;
    assert!(r.ground_contact_time_s <= r.final_time_s);
    assert!(
        (r.ground_contact_time_s - forward_liftoff).abs() <= h,
        "lift-off {} s, forward {forward_liftoff} s",
        r.ground_contact_time_s
    );
    // The push-off analysis of Simbody's trajectory: Newton's second law
    // for the whole body (ground impulse less the weight's = COM momentum
    // change) and the same jump as the forward check's.
    let a = r
        .forward_check
        .as_ref()
        .unwrap()
        .push_off
        .as_ref()
        .expect("analysed");
    assert!(a.liftoff);
    crate::common::assert_push_off_consistent(a, 1e-2, forward.jump_height_m, "forward check");
}

/// Issue 5's "done when" on the default study: solved, violation ≤ 1e-3,
/// Table 2's metrics inside the experimental ranges, forward check within
/// 1 cm.
#[test]
#[ignore = "the full 29-node solve takes about 2 minutes; scripts/full_solve.sh"]
fn full_jump_meets_the_papers_ranges() {
    let r = solve("models/jump_collocation.json", "full");
    let mut failed = Vec::new();
    let mut check = |ok: bool, what: String| {
        if !ok {
            failed.push(what);
        }
    };
    check(
        r.status == SqpStatus::Solved,
        format!("status {:?}", r.status),
    );
    let v = r.max_constraint_violation;
    check(v <= 1e-3, format!("violation {v:e}"));
    let h = r.jump_height_m;
    check((0.33..=0.41).contains(&h), format!("jump height {h} m"));
    let vel = r.liftoff_com_velocity_mps;
    check(
        (2.0..=2.5).contains(&vel),
        format!("lift-off velocity {vel} m/s"),
    );
    let t = r.ground_contact_time_s;
    check((0.25..=0.39).contains(&t), format!("contact time {t} s"));
    let f = r.peak_vertical_grf_bw;
    check(
        (2.5..=3.5).contains(&f),
        format!("peak vertical GRF {f} BW"),
    );
    let d = r.forward_check_difference_m.unwrap_or(f64::NAN);
    check(d.abs() <= 0.01, format!("forward check {d} m"));
    assert!(failed.is_empty(), "outside issue 5's targets: {failed:?}");
}

/// Hermite–Simpson on the default study: solved, violation ≤ 1e-3, and the
/// optimal excitations integrated forward jump as high as predicted within
/// 1 cm (the scheme's own prediction; Table 2's ranges are the default
/// scheme's test above).
#[test]
#[ignore = "the full Hermite–Simpson solve takes about 3 minutes; scripts/full_solve.sh"]
fn full_jump_by_hermite_simpson_is_solved_and_agrees() {
    assert_solved_and_forward_checked(&solve_by_hermite_simpson(
        "models/jump_collocation.json",
        "full_hs",
    ));
}

/// The shipped studies on the other models solve as the default study
/// does: status solved, violation at most 1e-3, forward check within 1 cm.
/// `jump_gait2392.json` (28 intervals) turns on the filter reset and the
/// second-order correction of every rejected full step (its
/// `line_search`), without which it cycles to its iteration limit
/// (docs/sqp.md); the filter is reset at least once.
#[test]
#[ignore = "three full solves, about 3 minutes on 2 cores; scripts/full_solve.sh"]
fn shipped_studies_on_other_models_are_solved_and_agree() {
    for (study, tag) in [
        ("models/jump_explicit.json", "full_explicit"),
        ("models/jump_jmp_strength.json", "full_jmp_strength"),
        ("models/jump_gait2392.json", "full_gait2392"),
    ] {
        let r = solve(study, tag);
        assert_solved_and_forward_checked(&r);
        if tag == "full_gait2392" {
            assert!(r.line_search.second_order_correction_every_rejected_step);
            assert!(r.line_search.filter_resets >= 1, "{:?}", r.line_search);
        }
    }
}

/// The paper's two methods on the full 29-node jump, both from the
/// bang-bang guess: direct shooting (forward sensitivities, the default)
/// against the collocation solve of the same study, run here. Shooting's
/// optimum is an integration of the model, so it must be solved within
/// the paper's 1e-3, agree with its Simbody forward check within 1 cm, and
/// jump as high as collocation predicts within 1 cm (the forward check's
/// tolerance).
#[test]
#[ignore = "the full shooting solve takes about 3 minutes on 2 cores; scripts/full_shooting.sh"]
fn full_jump_by_shooting_agrees_with_collocation() {
    let collocation = solve("models/jump_collocation.json", "full_collocation");
    let shooting = solve_with(
        "models/jump_collocation.json",
        "full_shooting",
        Overrides {
            method: Some("shooting".into()),
            ..Default::default()
        },
    );
    assert_eq!(shooting.method, leap::study::Method::Shooting);
    assert!(
        matches!(shooting.status, SqpStatus::Solved),
        "{}",
        shooting.message
    );
    assert!(shooting.max_constraint_violation <= 1e-3);
    let diff = shooting
        .forward_check_difference_m
        .expect("forward check ran");
    assert!(diff.abs() <= 0.01, "forward check differs by {diff} m");
    let gap = shooting.jump_height_m - collocation.jump_height_m;
    eprintln!(
        "shooting {:.2} cm in {} iterations, {:.0} s; collocation {:.2} cm in {} iterations, {:.1} s",
        100.0 * shooting.jump_height_m,
        shooting.iterations,
        shooting.wall_time_s,
        100.0 * collocation.jump_height_m,
        collocation.iterations,
        collocation.wall_time_s
    );
    assert!(
        gap.abs() <= 0.01,
        "shooting and collocation differ by {gap} m"
    );
}
