//! Direct collocation of the jump (Porsa et al. 2016): problem sizes, the
//! exact sparse Jacobian against finite differences, the sparsity pattern
//! at fresh random states, defects on a forward trajectory (convergence
//! order), the objective and the no-countermovement rows against
//! independent computations, and the partially separable structure.

use leap::integrator::{Dopri5, Dopri5Options, OdeSystem};
use leap::nlp::{check_elements, Nlp};
use leap::ocp::{JumpOcp, LiftOff, OcpOptions};
use leap::simulate::ExcitationSource;
use leap::transcription::*;
use std::sync::{Arc, OnceLock};

/// One problem and pattern for the whole file (tests run in parallel).
fn setup() -> &'static (Arc<JumpOcp>, StatePattern, Vec<f64>) {
    static S: OnceLock<(Arc<JumpOcp>, StatePattern, Vec<f64>)> = OnceLock::new();
    S.get_or_init(|| {
        let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
        let ocp = Arc::new(JumpOcp::new(&model, OcpOptions::default()).unwrap());
        let opts = TranscriptionOptions::default();
        let pattern = StatePattern::detect(&ocp, opts.pattern_samples, opts.pattern_seed).unwrap();
        let tr = Transcription::with_pattern(ocp.clone(), opts, pattern.clone()).unwrap();
        let (guess, _) = tr.bang_bang_guess().unwrap();
        (ocp, pattern, guess)
    })
}

fn transcription(options: TranscriptionOptions) -> Transcription {
    let (ocp, pattern, _) = setup();
    Transcription::with_pattern(ocp.clone(), options, pattern.clone()).unwrap()
}

/// The worst discrepancies of a Jacobian against finite differences.
#[derive(Debug, Default)]
struct FdReport {
    /// max |J − central| / max(1, |central|) over entries where f is smooth.
    worst: f64,
    worst_at: String,
    /// Entries where the one-sided differences disagree (a kink of f within
    /// the step: OpenSim's activation switch at u = a, the clamp at a_min,
    /// contact onset) and J equals one of them.
    kinks: usize,
    /// Entries that needed the smaller step (strong curvature: the fibre
    /// velocity of a muscle at minimum activation).
    refined: usize,
    /// Entries within 1e-6 of the difference only relative to the largest
    /// entry of their row (the differences' roundoff is relative to the
    /// row's terms), and the largest such error.
    row_scaled: usize,
    row_scaled_worst: f64,
    /// Largest |central| / max(1, max_j |J_ij|) outside the declared pattern.
    outside: f64,
    outside_at: String,
    entries: usize,
}

/// Central differences of every constraint row along variable `j`, step
/// `s` (and the one-sided ones).
fn differences(
    tr: &mut Transcription,
    x: &[f64],
    c0: &[f64],
    j: usize,
    s: f64,
) -> Vec<(f64, f64, f64)> {
    let m = c0.len();
    let (mut cp, mut cm) = (vec![0.0; m], vec![0.0; m]);
    let mut xp = x.to_vec();
    xp[j] = x[j] + s;
    tr.constraints(&xp, &mut cp).unwrap();
    xp[j] = x[j] - s;
    tr.constraints(&xp, &mut cm).unwrap();
    (0..m)
        .map(|i| {
            (
                (cp[i] - cm[i]) / (2.0 * s),
                (cp[i] - c0[i]) / s,
                (c0[i] - cm[i]) / s,
            )
        })
        .collect()
}

/// Compare the Jacobian at `x` with central differences of step 1e-6
/// (relative to max(1, |x_j|)); an entry that misses 1e-6 relative is
/// checked again with step 1e-8 and by Richardson extrapolation of steps
/// 2e-8 and 1e-8 (the differences converge to it as the step shrinks: the
/// fibre velocity of a muscle at minimum activation is strongly curved), or,
/// where the one-sided differences disagree, against
/// the one-sided difference it matches (a kink).
fn fd_check(tr: &mut Transcription, x: &[f64]) -> FdReport {
    let (n, m) = (tr.num_variables(), tr.num_constraints());
    let structure = tr.jacobian_structure();
    let mut jv = vec![0.0; structure.len()];
    tr.jacobian_values(x, &mut jv).unwrap();
    let mut by_col: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let mut row_max = vec![0.0f64; m];
    for (k, &(i, j)) in structure.iter().enumerate() {
        by_col[j].push((i, jv[k]));
        row_max[i] = row_max[i].max(jv[k].abs());
    }
    let mut c0 = vec![0.0; m];
    tr.constraints(x, &mut c0).unwrap();
    let mut rep = FdReport::default();
    let mut analytic = vec![None; m];
    for j in 0..n {
        let scale = x[j].abs().max(1.0);
        let d = differences(tr, x, &c0, j, 1e-6 * scale);
        let mut fine: Option<Vec<(f64, f64, f64)>> = None;
        let mut double: Option<Vec<(f64, f64, f64)>> = None;
        for &(i, v) in &by_col[j] {
            analytic[i] = Some(v);
        }
        for i in 0..m {
            let (central, fwd, bwd) = d[i];
            match analytic[i] {
                Some(a) => {
                    rep.entries += 1;
                    let err = (a - central).abs() / central.abs().max(1.0);
                    if err <= 1e-6 {
                        continue;
                    }
                    let f = fine.get_or_insert_with(|| differences(tr, x, &c0, j, 1e-8 * scale));
                    let err2 = (a - f[i].0).abs() / f[i].0.abs().max(1.0);
                    if err2 <= 1e-6 {
                        rep.refined += 1;
                        continue;
                    }
                    // Richardson extrapolation of steps 2e-8 and 1e-8 (error
                    // O(step⁴)) for the most strongly curved entries.
                    let f2 = double.get_or_insert_with(|| differences(tr, x, &c0, j, 2e-8 * scale));
                    let rich = (4.0 * f[i].0 - f2[i].0) / 3.0;
                    if (a - rich).abs() / rich.abs().max(1.0) <= 1e-6 {
                        rep.refined += 1;
                        continue;
                    }
                    // A kink: the one-sided derivatives differ and J is one of
                    // them (to the O(step) error of a one-sided difference).
                    let (fwd2, bwd2) = (f[i].1, f[i].2);
                    let kink = (fwd2 - bwd2).abs() > 1e-3 * fwd2.abs().max(bwd2.abs()).max(1.0);
                    if kink && (a - fwd2).abs().min((a - bwd2).abs()) <= 1e-4 * a.abs().max(1.0) {
                        rep.kinks += 1;
                        continue;
                    }
                    // Roundoff of the differences: judge against the row's scale.
                    let row_err = (a - central).abs().min((a - f[i].0).abs()) / row_max[i].max(1.0);
                    rep.row_scaled_worst = rep.row_scaled_worst.max(row_err);
                    if row_err <= 1e-6 {
                        rep.row_scaled += 1;
                    } else if row_err > rep.worst {
                        rep.worst = row_err;
                        rep.worst_at = format!("∂{}/∂{}: {a} vs {central} (step 1e-8: {}; fwd {fwd}, bwd {bwd}; row scale {})", tr.constraint_name(i), tr.variable_name(j), f[i].0, row_max[i]);
                    }
                }
                None => {
                    let r = central.abs() / row_max[i].max(1.0);
                    if r > rep.outside {
                        rep.outside = r;
                        rep.outside_at = format!(
                            "∂{}/∂{} = {central}",
                            tr.constraint_name(i),
                            tr.variable_name(j)
                        );
                    }
                }
            }
        }
        for &(i, _) in &by_col[j] {
            analytic[i] = None;
        }
    }
    rep
}

/// A point near `x`: states and controls moved by 2 % of their range (at
/// most 2), kept inside the bounds.
fn perturbed(tr: &Transcription, x: &[f64], seed: u64) -> Vec<f64> {
    perturbed_by(tr, x, seed, 0.02)
}

fn perturbed_by(tr: &Transcription, x: &[f64], seed: u64, amplitude: f64) -> Vec<f64> {
    let n = x.len();
    let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
    tr.variable_bounds(&mut lo, &mut hi);
    let mut y = x.to_vec();
    let mut s = seed;
    for i in 0..n {
        // SplitMix64: a uniform number in [-1, 1).
        s = s.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^= z >> 31;
        let r = (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0;
        let width = (hi[i] - lo[i]).min(2.0);
        // Distinct margins keep clipped values apart (an activation equal
        // to its excitation sits on OpenSim's activation/deactivation switch).
        let margin = (1e-4 + 1e-3 * (i % 7) as f64) * width;
        y[i] = (x[i] + amplitude * width * r).clamp(lo[i] + margin, hi[i] - margin);
    }
    y
}

#[test]
fn sizes_bounds_and_elements() {
    let (ocp, _, guess) = setup();
    let tr = transcription(TranscriptionOptions::default());
    let (n, m) = (tr.num_variables(), tr.num_constraints());
    // Porsa et al.: 28 free nodes of 62 states and 24 excitations, plus t_f;
    // 28·62 midpoint defects, 7 no-countermovement rows, one lift-off row;
    // then leap's 28 no-descent rows Ẏ_C(t_k) ≥ 0.
    assert_eq!(n, 2409);
    assert_eq!(tr.defect_rows(), 0..1736);
    assert_eq!(tr.no_countermovement_rows(), 1736..1743);
    assert_eq!(tr.liftoff_row(), 1743);
    assert_eq!(tr.no_descent_rows(), 1744..1772);
    assert_eq!(m, 1772);
    let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
    tr.variable_bounds(&mut lo, &mut hi);
    assert!(lo.iter().zip(&hi).all(|(a, b)| a <= b));
    assert_eq!((lo[n - 1], hi[n - 1]), (0.1, 1.0));
    // Excitations in [min_control, 1], activations in [a_min, 1].
    for k in 0..24 {
        let c = tr.control_index(3, k).unwrap();
        assert_eq!((lo[c], hi[c]), (0.01, 1.0));
        let a = tr.state_index(3, 38 + k).unwrap();
        assert_eq!((lo[a], hi[a]), (0.01, 1.0));
    }
    // The start and the guess lie inside the bounds.
    assert!(ocp
        .x0()
        .iter()
        .enumerate()
        .all(|(i, v)| (ocp.state_lower[i]..=ocp.state_upper[i]).contains(v)));
    assert!(guess
        .iter()
        .enumerate()
        .all(|(i, v)| (lo[i]..=hi[i]).contains(v)));
    let (mut cl, mut cu) = (vec![0.0; m], vec![0.0; m]);
    tr.constraint_bounds(&mut cl, &mut cu);
    assert!(cl[..1736].iter().chain(&cu[..1736]).all(|&v| v == 0.0));
    assert!(
        cl[1736..1743].iter().all(|&v| v == f64::NEG_INFINITY)
            && cu[1736..1743].iter().all(|&v| v == 0.0)
    );
    assert_eq!((cl[1743], cu[1743]), (f64::NEG_INFINITY, 0.01));
    assert!(cl[1744..].iter().all(|&v| v == 0.0) && cu[1744..].iter().all(|&v| v == f64::INFINITY));
    assert_eq!(tr.jacobian_stats().nnz_no_descent, 28 * 14);
    // Jacobian pattern: no duplicates, in range, sizes as reported.
    let s = tr.jacobian_structure();
    let mut sorted = s.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), s.len(), "duplicate Jacobian entries");
    assert!(s.iter().all(|&(i, j)| i < m && j < n));
    let st = tr.jacobian_stats();
    eprintln!("{st:#?}");
    assert_eq!(st.nnz, tr.jacobian_nnz());
    assert_eq!(st.nnz, s.len());
    assert_eq!(st.state_equation_entries, 5332);
    // Each defect block: both nodes' columns of ∂f/∂(x, u) ∪ I, and t_f.
    let f_x_and_identity: usize = (0..62)
        .map(|r| {
            tr.pattern().rows[r].iter().filter(|&&c| c < 62).count()
                + usize::from(!tr.pattern().contains(r, r))
        })
        .sum();
    let f_u: usize = (0..62)
        .map(|r| tr.pattern().rows[r].iter().filter(|&&c| c >= 62).count())
        .sum();
    assert_eq!(st.nnz_interval, 2 * (f_x_and_identity + f_u) + 62);
    assert_eq!(st.nnz_first_interval, f_x_and_identity + f_u + 62);
    assert_eq!(st.nnz_defects, st.nnz_first_interval + 27 * st.nnz_interval);
    // The structure of ∂f/∂(x, u): q̇ rows the identity on q̇; q̈ rows dense
    // over q, q̇ and l^M, not a or u (Thelen's tendon force depends on the
    // fibre and MTU lengths only); activation rows on a_i and u_i.
    for i in 0..7 {
        assert_eq!(tr.pattern().rows[i], vec![7 + i]);
        assert_eq!(tr.pattern().rows[7 + i], (0..38).collect::<Vec<_>>());
    }
    for k in 0..24 {
        assert_eq!(tr.pattern().rows[38 + k], vec![38 + k, 62 + k]);
        let r = &tr.pattern().rows[14 + k];
        assert!(
            r.contains(&(14 + k))
                && r.contains(&(38 + k))
                && r.iter().all(|&c| c < 7 || c == 14 + k || c == 38 + k),
            "{r:?}"
        );
    }
    // Vasti span the knee only; gastrocnemii the knee and the ankle.
    let names = ocp.eq.state_names();
    let row = |muscle: &str| {
        tr.pattern().rows[names
            .iter()
            .position(|s| *s == format!("/forceset/{muscle}/fiber_length"))
            .unwrap()]
        .clone()
    };
    assert_eq!(row("vas_int_r"), vec![4, 30, 54]);
    assert_eq!(row("med_gas_r"), vec![4, 5, 32, 56]);
    // The partially separable structure.
    let el = tr.elements();
    check_elements(&el, n, m).unwrap();
    // Per interval, rows with the same node columns share an element: each
    // q̇ row (q_j, q̇_j), the q̈ rows together (q, q̇, l^M), each fibre-length
    // row, each activation row (a_i, u_i): 7 + 1 + 24 + 24 = 56 groups.
    // Then one element per no-countermovement row, the objective with the
    // lift-off row, and one per no-descent row (the node's q, q̇).
    assert_eq!(el.len(), 56 * 28 + 7 + 1 + 28);
    for (k, row) in (1..=28).zip(tr.no_descent_rows()) {
        let e = &el[el.len() - 29 + k];
        assert_eq!(e.constraints, vec![row]);
        assert_eq!(
            e.variables,
            (0..14).map(|c| (k - 1) * 86 + c).collect::<Vec<_>>()
        );
    }
    assert_eq!(el.iter().filter(|e| e.objective).count(), 1);
    let mut owner = vec![0; m];
    for (e, x) in el.iter().enumerate() {
        for &i in &x.constraints {
            owner[i] = e;
        }
    }
    // Interval 2: the q̈ rows' element spans q, q̇ and l^M of nodes 1 and 2
    // and t_f; an activation row's element a_i, u_i of both nodes and t_f.
    let qdd = &el[owner[62 + 7]];
    assert_eq!(qdd.constraints, (62 + 7..62 + 14).collect::<Vec<_>>());
    assert_eq!(qdd.variables.len(), 2 * (7 + 7 + 24) + 1);
    assert_eq!(
        el[owner[62 + 38]].variables,
        vec![38, 62, 86 + 38, 86 + 62, n - 1]
    );
    // Blocks for the block-diagonal Hessian approximation: only the q̈
    // elements declare them; one block of the coordinates' values and
    // speeds at both nodes with t_f, then one per muscle, its fibre length
    // at both nodes.
    assert_eq!(el.iter().filter(|e| !e.blocks.is_empty()).count(), 28);
    let name = |j: usize| tr.variable_name(j);
    assert_eq!(qdd.blocks.len(), 1 + 24);
    assert_eq!(qdd.blocks[0].len(), 2 * 14 + 1);
    for &a in &qdd.blocks[0] {
        let v = name(qdd.variables[a]);
        assert!(
            v == "t_f" || v.ends_with("/value") || v.ends_with("/speed"),
            "{v}"
        );
    }
    for leaf in &qdd.blocks[1..] {
        let names: Vec<String> = leaf.iter().map(|&a| name(qdd.variables[a])).collect();
        assert_eq!(names.len(), 2);
        assert!(names[0].starts_with("node 1 ") && names[0].ends_with("/fiber_length"));
        assert_eq!(names[0].replace("node 1 ", "node 2 "), names[1]);
    }
    // Every Jacobian entry lies inside its row's element.
    for &(i, j) in &s {
        assert!(
            el[owner[i]].variables.binary_search(&j).is_ok(),
            "entry ({i}, {j}) outside its element"
        );
    }
    // Names.
    assert_eq!(tr.variable_name(n - 1), "t_f");
    assert_eq!(
        tr.variable_name(86 + 3),
        "node 2 /jointset/hip_r/hip_flexion_r/value"
    );
    assert!(tr
        .constraint_name(62 + 7)
        .starts_with("defect of interval 2 in /jointset/ground_pelvis/pelvis_tilt/speed"));
}

#[test]
fn settings_errors_name_what_is_wrong() {
    let (ocp, pattern, _) = setup();
    let with =
        |o: OcpOptions| JumpOcp::from_parts(ocp.eq.clone(), ocp.laws.clone(), ocp.squat.clone(), o);
    let e = with(OcpOptions {
        final_time_bounds: [0.5, 0.2],
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("final_time_bounds"), "{e}");
    let e = with(OcpOptions {
        speed_bound: 0.0,
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("speed_bound"), "{e}");
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    for w in [0.0, -0.02, f64::NAN] {
        let Err(e) = JumpOcp::new(
            &model,
            OcpOptions {
                fiber_clamp_smoothing: Some(w),
                ..Default::default()
            },
        ) else {
            panic!("a fibre clamp band of {w} was accepted");
        };
        assert!(e.to_string().contains("fiber_clamp_smoothing"), "{e}");
    }
    let e = with(OcpOptions {
        fiber_length_bounds: [0.2, 0.5],
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("the static squat violates the bounds of /forceset/")
            && e.contains("(the problem's fiber_length_bounds"),
        "{e}"
    );
    let e = with(OcpOptions {
        fiber_length_bounds: [1.5, 1.2],
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("fiber_length_bounds"), "{e}");
    // Lift-off as an equality.
    let eq_ocp = Arc::new(
        with(OcpOptions {
            liftoff: LiftOff::ForceEquals { fraction: 0.05 },
            ..Default::default()
        })
        .unwrap(),
    );
    let tr = Transcription::with_pattern(eq_ocp, TranscriptionOptions::default(), pattern.clone())
        .unwrap();
    let (mut cl, mut cu) = (
        vec![0.0; tr.num_constraints()],
        vec![0.0; tr.num_constraints()],
    );
    tr.constraint_bounds(&mut cl, &mut cu);
    assert_eq!((cl[tr.liftoff_row()], cu[tr.liftoff_row()]), (0.05, 0.05));
    // Too few intervals for the no-countermovement rows; a wrong pattern.
    let e = Transcription::with_pattern(
        ocp.clone(),
        TranscriptionOptions {
            num_mesh_intervals: 5,
            ..Default::default()
        },
        pattern.clone(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("num_mesh_intervals = 5"), "{e}");
    let mut bad = pattern.clone();
    bad.nu = 3;
    assert!(
        Transcription::with_pattern(ocp.clone(), TranscriptionOptions::default(), bad).is_err()
    );
    // Guesses.
    let tr = transcription(TranscriptionOptions::default());
    let x0 = ocp.x0().to_vec();
    let u0 = ocp.u0().to_vec();
    let e = tr
        .guess_from_trajectory(
            &[0.0, 0.2, 0.1],
            &[x0.clone(), x0.clone(), x0.clone()],
            &[u0.clone(), u0.clone(), u0.clone()],
            0.1,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("not increasing at index 2"), "{e}");
    let e = tr
        .guess_from_trajectory(
            &[0.0, 0.2],
            &[x0.clone(), x0.clone()],
            &[u0.clone(), u0.clone()],
            0.3,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("ends at 0.2 s"), "{e}");
    let e = tr
        .guess_from_trajectory(
            &[0.0, 0.2],
            &[x0.clone(), x0[..10].to_vec()],
            &[u0.clone(), u0.clone()],
            0.1,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("state 1 has 10 values"), "{e}");
    // A state outside its bounds is projected into them and reported: the
    // knee angle rising to the squat's in degrees (×180/π) after t = 0.25 s,
    // so outside at the last nodes alone; the squat lies within every bound.
    let knee = ocp
        .eq
        .state_names()
        .iter()
        .position(|n| n.ends_with("/knee_angle_r/value"))
        .unwrap();
    let mut bent = x0.clone();
    bent[knee] = x0[knee].to_degrees();
    let (tf, times) = (0.3, [0.0, 0.25, 0.3]);
    let (v, projected) = tr
        .guess_from_trajectory(
            &times,
            &[x0.clone(), x0.clone(), bent.clone()],
            &[u0.clone(), u0.clone(), u0.clone()],
            tf,
        )
        .unwrap();
    let mesh = tr.mesh_times(tf);
    let (lo, hi) = (ocp.state_lower[knee], ocp.state_upper[knee]);
    // The resampled knee angle at each node, as the guess interpolates it.
    let resampled = |t: f64| {
        if t <= 0.25 {
            x0[knee]
        } else {
            x0[knee] + (t - 0.25) / 0.05 * (bent[knee] - x0[knee])
        }
    };
    let outside = mesh[1..]
        .iter()
        .filter(|&&t| !(lo..=hi).contains(&resampled(t)))
        .count();
    assert!(0 < outside && outside < mesh.len() - 1, "{outside}");
    assert_eq!(projected.len(), 1, "{projected:?}");
    let p = &projected[0];
    assert_eq!(p.name, ocp.eq.state_names()[knee]);
    assert_eq!(p.nodes, outside);
    assert_eq!((p.lower, p.upper), (lo, hi));
    // The farthest is the last node's, the whole degrees value.
    assert_eq!((p.value, p.time_s), (bent[knee], *mesh.last().unwrap()));
    assert!(p.likely_degrees, "{p}");
    assert!(p.to_string().contains("inDegrees=yes"), "{p}");
    assert!(p.bound.contains("coordinates["), "{}", p.bound);
    // Projected: every node's knee angle within its bounds.
    for k in 1..mesh.len() {
        let j = tr.state_index(k, knee).unwrap();
        assert!((lo..=hi).contains(&v[j]), "node {k}: {}", v[j]);
    }
    // The squat alone: nothing projected.
    let (_, projected) = tr
        .guess_from_trajectory(
            &[0.0, tf],
            &[x0.clone(), x0.clone()],
            &[u0.clone(), u0.clone()],
            tf,
        )
        .unwrap();
    assert!(projected.is_empty(), "{projected:?}");
    // Evaluation errors instead of panics.
    let mut tr = tr;
    let mut c = vec![0.0; 3];
    let v = tr.constant_guess(0.3);
    assert!(tr
        .constraints(&v, &mut c)
        .unwrap_err()
        .to_string()
        .contains("length 3"));
    let mut c = vec![0.0; tr.num_constraints()];
    let mut w = v.clone();
    w[100] = f64::NAN;
    let e = tr.constraints(&w, &mut c).unwrap_err().to_string();
    assert!(e.contains("node 2 /forceset/") && e.contains("NaN"), "{e}");
}

#[test]
fn jacobian_matches_finite_differences_midpoint() {
    let (_, _, guess) = setup();
    let mut tr = transcription(TranscriptionOptions::default());
    for (name, x) in [
        ("bang-bang guess", guess.clone()),
        ("perturbed guess", perturbed(&tr, guess, 7)),
    ] {
        let r = fd_check(&mut tr, &x);
        eprintln!("midpoint, {name}: {} entries, worst {:.2e} ({}), kinks {}, refined {}, row-scaled {} (worst {:.1e}), outside the pattern {:.2e} ({})", r.entries, r.worst, r.worst_at, r.kinks, r.refined, r.row_scaled, r.row_scaled_worst, r.outside, r.outside_at);
        assert!(r.worst <= 1e-6, "{name}: {}", r.worst_at);
        assert!(r.outside <= 1e-7, "{name}: {}", r.outside_at);
        // At the guess, muscles that are off sit at a = u = a_min: on the
        // activation switch and the clamp (6 entries per muscle and interval).
        let allowed = if name == "bang-bang guess" {
            6 * 8 * 28 + r.entries / 1000
        } else {
            r.entries / 1000
        };
        assert!(r.kinks <= allowed, "{name}: {} kinks", r.kinks);
    }
}

#[test]
fn jacobian_matches_finite_differences_other_schemes() {
    let (_, _, guess) = setup();
    // A coarser mesh keeps the column count small; the guess is resampled.
    let full = transcription(TranscriptionOptions::default());
    let traj = full.unpack(guess);
    for scheme in [
        Scheme::Trapezoidal,
        Scheme::HermiteSimpson,
        Scheme::BackwardEuler,
    ] {
        let mut tr = transcription(TranscriptionOptions {
            num_mesh_intervals: 10,
            scheme,
            ..Default::default()
        });
        let (x, _) = tr
            .guess_from_trajectory(
                &traj.time,
                &traj.states,
                &traj.controls,
                full.final_time(guess),
            )
            .unwrap();
        // Hermite–Simpson's centre state x_c = x̄ + h(f_{k−1} − f_k)/8 leaves
        // the physiological range at 10 intervals if perturbed fibres move
        // at metres per second: a smaller perturbation there.
        let x = perturbed_by(
            &tr,
            &x,
            11,
            if scheme == Scheme::HermiteSimpson {
                1e-4
            } else {
                0.02
            },
        );
        let r = fd_check(&mut tr, &x);
        eprintln!("{scheme:?}: {} entries, worst {:.2e} ({}), kinks {}, refined {}, row-scaled {} (worst {:.1e}), outside the pattern {:.2e} ({})", r.entries, r.worst, r.worst_at, r.kinks, r.refined, r.row_scaled, r.row_scaled_worst, r.outside, r.outside_at);
        assert!(r.worst <= 1e-6, "{scheme:?}: {}", r.worst_at);
        assert!(r.outside <= 1e-7, "{scheme:?}: {}", r.outside_at);
        assert!(r.kinks <= r.entries / 1000, "{scheme:?}: {} kinks", r.kinks);
    }
}

#[test]
fn compressed_uncompressed_and_parallel_jacobians_agree() {
    let (_, _, guess) = setup();
    for scheme in [Scheme::MidpointEuler, Scheme::HermiteSimpson] {
        let mut a = transcription(TranscriptionOptions {
            threads: 1,
            scheme,
            ..Default::default()
        });
        let mut b = transcription(TranscriptionOptions {
            threads: 2,
            scheme,
            compress_columns: false,
            ..Default::default()
        });
        let x = perturbed_by(&a, guess, 3, 1e-3);
        let (mut ja, mut jb) = (vec![0.0; a.jacobian_nnz()], vec![0.0; b.jacobian_nnz()]);
        a.jacobian_values(&x, &mut ja).unwrap();
        b.jacobian_values(&x, &mut jb).unwrap();
        assert_eq!(a.jacobian_structure(), b.jacobian_structure());
        let worst = ja
            .iter()
            .zip(&jb)
            .map(|(p, q)| (p - q).abs() / p.abs().max(1.0))
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-12,
            "{scheme:?}: compressed vs uncompressed: {worst:e}"
        );
        let (mut ca, mut cb) = (
            vec![0.0; a.num_constraints()],
            vec![0.0; b.num_constraints()],
        );
        a.constraints(&x, &mut ca).unwrap();
        b.constraints(&x, &mut cb).unwrap();
        assert_eq!(ca, cb, "{scheme:?}");
        assert!(a.jacobian_stats().colors < b.jacobian_stats().colors);
    }
}

/// Direct shooting's point Jacobian walks the muscle paths once per point
/// and lifts them into each pass's lanes: the same entries, to rounding,
/// as walking them in every pass (the way of collocation's Jacobian, which
/// the tests above check against finite differences), at points along the
/// bang-bang guess and perturbed ones.
#[test]
fn point_jacobian_with_paths_walked_once_matches_every_pass() {
    let (ocp, pattern, guess) = setup();
    let (nx, nu) = (ocp.nx(), ocp.nu());
    let mut once = PointJacobian::new(ocp, pattern).unwrap();
    let mut every = PointJacobian::new(ocp, pattern).unwrap();
    assert!(once.walks_paths_once());
    every.walk_paths_in_every_pass();
    assert!(!every.walks_paths_once());
    let entries = once.entries().to_vec();
    assert_eq!(entries, every.entries());
    let tr = transcription(TranscriptionOptions::default());
    let perturbed = perturbed_by(&tr, guess, 5, 1e-2);
    let (mut g1, mut g2) = (vec![0.0; nx + 2], vec![0.0; nx + 2]);
    let (mut j1, mut j2) = (vec![0.0; entries.len()], vec![0.0; entries.len()]);
    let (mut checked, mut worst) = (0, 0.0f64);
    for v in [guess, &perturbed] {
        for node in [2, 6, 10, 16, 22, 27] {
            // Node 0 (the squat) is not among the variables.
            let at = (nx + nu) * (node - 1);
            let (x, u) = (&v[at..at + nx], &v[at + nx..at + nx + nu]);
            once.eval(ocp, x, u, &mut g1, &mut j1).unwrap();
            every.eval(ocp, x, u, &mut g2, &mut j2).unwrap();
            // The paths' unit forces scaled by the tension instead of the
            // tension carried along the path: rounding apart, which the
            // muscle moments' cancellation in q̈ (kN·m for rad/s²) enlarges.
            for (i, (a, b)) in g1.iter().zip(&g2).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-10 * b.abs().max(1.0),
                    "node {node}, output {i}: {a} against {b}"
                );
            }
            // Relative to the largest entry of the row (the sums run in
            // another order).
            let mut row_max = vec![0.0f64; nx + 2];
            for (&(r, _), b) in entries.iter().zip(&j2) {
                row_max[r] = row_max[r].max(b.abs());
            }
            for (k, (&(r, c), (a, b))) in entries.iter().zip(j1.iter().zip(&j2)).enumerate() {
                worst = worst.max((a - b).abs() / row_max[r].max(1.0));
                assert!(
                    (a - b).abs() <= 1e-10 * row_max[r].max(1.0),
                    "node {node}, entry {k} (row {r}, column {c}): {a} against {b}"
                );
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 12);
    assert!(j1.iter().any(|&v| v != 0.0));
    // A non-finite state is named, not taken for paths of another point.
    let mut bad = guess[..nx].to_vec();
    bad[3] = f64::NAN;
    let e = once
        .eval(ocp, &bad, &guess[nx..nx + nu], &mut g1, &mut j1)
        .unwrap_err();
    assert!(e.contains("state 3 is NaN"), "{e}");
    eprintln!("point Jacobian, paths walked once against every pass: {worst:.1e} of the row's largest entry");
}

#[test]
fn pattern_holds_at_fresh_random_states() {
    let (ocp, pattern, _) = setup();
    let v = pattern.violations(ocp, 150, 2024);
    assert!(v.is_empty(), "entries outside the pattern: {v:?}");
    assert_eq!(pattern.samples_rejected, 0);
}

/// ẋ = f(x, u(t)) with u linear in time from u_a (t = 0) to u_b (t = T).
struct Ramp<'a> {
    ocp: &'a JumpOcp,
    ws: leap::ode::StateWorkspace<f64>,
    ua: Vec<f64>,
    ub: Vec<f64>,
    t_end: f64,
    u: Vec<f64>,
}

impl Ramp<'_> {
    fn control(&self, t: f64) -> Vec<f64> {
        self.ua
            .iter()
            .zip(&self.ub)
            .map(|(a, b)| a + (b - a) * t / self.t_end)
            .collect()
    }
}

impl OdeSystem for Ramp<'_> {
    fn dim(&self) -> usize {
        self.ocp.nx()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        self.u = self.control(t);
        self.ocp
            .state_rates(&mut self.ws, x, &self.u, dx)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }
}

#[test]
fn defects_vanish_at_the_schemes_order_on_a_forward_trajectory() {
    let (ocp, _, _) = setup();
    // Excitations ramp linearly from the squat's to the bang-bang pattern's
    // (piecewise-linear controls are exact on every mesh). Low-activation
    // fibres are stiff (time constants of ~0.1 ms), so the asymptotic order
    // shows from 32 intervals in 0.1 s on; up to 16 the ratio is ~4.
    let t_end = 0.1;
    let mut ub = vec![0.0; ocp.nu()];
    ocp.bang_bang().at(0.0, &mut ub);
    let mut sys = Ramp {
        ocp,
        ws: ocp.eq.workspace(),
        ua: ocp.u0().to_vec(),
        ub,
        t_end,
        u: vec![],
    };
    let finest = 128;
    let mut ig = Dopri5::new(
        &mut sys,
        0.0,
        ocp.x0(),
        Dopri5Options {
            accuracy: 1e-11,
            max_steps: 1_000_000,
            ..Default::default()
        },
    )
    .unwrap();
    let mut states = vec![ocp.x0().to_vec()];
    for k in 1..=finest {
        let t = t_end * k as f64 / finest as f64;
        while ig.t() < t {
            ig.step(&mut sys, t).unwrap();
        }
        states.push(ig.x().to_vec());
    }
    let mut worst_at_finest = Vec::new();
    for scheme in [
        Scheme::Trapezoidal,
        Scheme::MidpointEuler,
        Scheme::HermiteSimpson,
        Scheme::BackwardEuler,
    ] {
        let mut last: Option<f64> = None;
        for big_n in [32, 64, 128] {
            let mut tr = transcription(TranscriptionOptions {
                num_mesh_intervals: big_n,
                scheme,
                ..Default::default()
            });
            let stride = finest / big_n;
            let xs: Vec<Vec<f64>> = (0..=big_n).map(|k| states[k * stride].clone()).collect();
            let us: Vec<Vec<f64>> = tr
                .mesh_times(t_end)
                .iter()
                .map(|&t| sys.control(t))
                .collect();
            let v = tr.pack(&xs, &us, t_end).unwrap();
            let mut c = vec![0.0; tr.num_constraints()];
            tr.constraints(&v, &mut c).unwrap();
            let worst = c[tr.defect_rows()]
                .iter()
                .fold(0.0f64, |m, d| m.max(d.abs()));
            eprintln!(
                "{scheme:?}, N = {big_n}: max |defect| {worst:.3e}{}",
                last.map(|l| format!(", ratio {:.2}", l / worst))
                    .unwrap_or_default()
            );
            worst_at_finest.push((scheme, worst));
            if let Some(l) = last {
                // Local truncation error O(h³) (Hermite–Simpson O(h⁵),
                // backward Euler O(h²)): halving h divides it by ~8 (~32,
                // ~4), less where f has kinks (passive fibre force at
                // l̃ = 1, the tendon's toe region). The second-order
                // schemes' bound lies between their ratio 8 and a first
                // order's 4 (Hermite–Simpson is held to it too, its kinks
                // keeping it near 8). Backward Euler's lies between its 4
                // and a zeroth order's 2, at 2^1.5 (halfway on a log
                // scale) from 32 to 64 intervals and at 3.5 from 64 to 128:
                // the sharper the activation switch, the finer the mesh on
                // which the ratio reaches its asymptote (from 32 to 64
                // intervals 3.64 at b = 50, 3.48 at b = 200; from 64 to
                // 128, 3.96 and 4.01).
                let want = match scheme {
                    Scheme::BackwardEuler if big_n < finest => 2f64.powf(1.5),
                    Scheme::BackwardEuler => 3.5,
                    _ => 5.5,
                };
                assert!(
                    l / worst > want,
                    "{scheme:?}: N = {big_n}: ratio {}",
                    l / worst
                );
            }
            last = Some(worst);
        }
        // Backward Euler is first order: its size is checked by the ratio
        // above (O(h²) per step), not against the second-order schemes'.
        if scheme != Scheme::BackwardEuler {
            assert!(last.unwrap() < 2e-4, "{scheme:?}: {last:?}");
        }
    }
    // Hermite–Simpson is far more accurate on the finest mesh.
    let at = |s: Scheme| {
        worst_at_finest
            .iter()
            .rev()
            .find(|(t, _)| *t == s)
            .unwrap()
            .1
    };
    assert!(
        at(Scheme::HermiteSimpson) < 0.2 * at(Scheme::Trapezoidal).min(at(Scheme::MidpointEuler))
    );
}

#[test]
fn objective_and_path_rows_match_independent_computations() {
    let (ocp, _, guess) = setup();
    let mut tr = transcription(TranscriptionOptions::default());
    let x = perturbed(&tr, guess, 5);
    let eq = &ocp.eq;
    let (n, big_n) = (eq.nq(), 28);
    let g = 9.80665;
    assert_eq!(ocp.gravity, g);
    // J = Y_C + Ẏ_C²/(2g) at the final node, from the multibody directly.
    let xn = tr.node_state(&x, big_n).to_vec();
    let mut w = eq.multibody.workspace::<f64>();
    eq.multibody.set_state(&mut w, &xn[..n], &xn[n..2 * n]);
    let (yc, vc) = (
        eq.multibody.com_position(&w)[1],
        eq.multibody.com_velocity(&w)[1],
    );
    let f = tr.objective(&x).unwrap();
    assert!(
        (f + yc + vc * vc / (2.0 * g)).abs() < 1e-14,
        "{f} vs {}",
        -(yc + vc * vc / (2.0 * g))
    );
    // The gradient against central differences.
    let mut grad = vec![0.0; x.len()];
    tr.gradient(&x, &mut grad).unwrap();
    let mut xp = x.clone();
    for j in 0..x.len() {
        let s = 1e-6 * x[j].abs().max(1.0);
        xp[j] = x[j] + s;
        let fp = tr.objective(&xp).unwrap();
        xp[j] = x[j] - s;
        let fm = tr.objective(&xp).unwrap();
        xp[j] = x[j];
        let fd = (fp - fm) / (2.0 * s);
        assert!(
            (grad[j] - fd).abs() <= 1e-7 * fd.abs().max(1.0),
            "∂f/∂{}: {} vs {fd}",
            tr.variable_name(j),
            grad[j]
        );
    }
    // Ÿ_C at nodes 0..7 from q̈ = f(x, u) and com_acceleration; the
    // vertical ground force at the final node.
    let mut c = vec![0.0; tr.num_constraints()];
    tr.constraints(&x, &mut c).unwrap();
    let mut ws = eq.workspace::<f64>();
    let mut dx = vec![0.0; eq.nx()];
    let ydd: Vec<f64> = (0..=7)
        .map(|k| {
            eq.rhs(
                &ocp.laws,
                &mut ws,
                tr.node_state(&x, k),
                tr.node_control(&x, k),
                &mut dx,
            )
            .unwrap();
            eq.multibody.com_acceleration(&ws.mb, &dx[n..2 * n])[1]
        })
        .collect();
    assert!(
        ydd[0].abs() < 1e-6,
        "the static squat accelerates: {}",
        ydd[0]
    );
    for j in 0..7 {
        let want = ydd[j] - ydd[j + 1];
        assert!(
            (c[1736 + j] - want).abs() <= 1e-12 * want.abs().max(1.0),
            "row {j}: {} vs {want}",
            c[1736 + j]
        );
    }
    eq.rhs(&ocp.laws, &mut ws, &xn, tr.node_control(&x, big_n), &mut dx)
        .unwrap();
    let fy: f64 = ws.sphere_force.iter().map(|f| f[1]).sum();
    let weight = eq.model.total_mass() * g;
    assert!((c[1743] - fy / weight).abs() <= 1e-12 * (fy / weight).abs().max(1.0));
    // No descent: row 1743 + k is Ẏ_C at node k, which must equal the rate
    // of Y_C along q̇ (central difference of the COM height).
    for k in 1..=big_n {
        let xk = tr.node_state(&x, k);
        let (q, qd) = (&xk[..n], &xk[n..2 * n]);
        let eps = 1e-6;
        let mut y_at = |s: f64| {
            let qs: Vec<f64> = q.iter().zip(qd).map(|(a, b)| a + s * b).collect();
            eq.multibody.set_state(&mut w, &qs, qd);
            eq.multibody.com_position(&w)[1]
        };
        let (yp, ym) = (y_at(eps), y_at(-eps));
        let want = (yp - ym) / (2.0 * eps);
        assert!(
            (c[1743 + k] - want).abs() <= 1e-7 * want.abs().max(1.0),
            "node {k}: Ẏ_C {} vs dY_C/dt {want}",
            c[1743 + k]
        );
    }
    // The defects of interval 3 (midpoint Euler) by hand.
    let h = tr.final_time(&x) / 28.0;
    let xm: Vec<f64> = tr
        .node_state(&x, 2)
        .iter()
        .zip(tr.node_state(&x, 3))
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    let um: Vec<f64> = tr
        .node_control(&x, 2)
        .iter()
        .zip(tr.node_control(&x, 3))
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    eq.rhs(&ocp.laws, &mut ws, &xm, &um, &mut dx).unwrap();
    for r in 0..62 {
        let want = tr.node_state(&x, 3)[r] - tr.node_state(&x, 2)[r] - h * dx[r];
        assert!((c[2 * 62 + r] - want).abs() <= 1e-12 * want.abs().max(1.0));
    }
}

#[test]
fn bang_bang_guess_follows_the_forward_jump() {
    let (ocp, _, guess) = setup();
    let tr = transcription(TranscriptionOptions::default());
    let (summary, traj) = ocp.simulate_bang_bang(1e-6).unwrap();
    let tf = summary.liftoff_time_s.unwrap();
    assert!((0.2..0.4).contains(&tf), "lift-off at {tf} s");
    assert_eq!(tr.final_time(guess), tf);
    // Node 0 is the squat; node N is the state at lift-off.
    let mesh = tr.unpack(guess);
    assert_eq!(mesh.states[0], ocp.x0());
    assert_eq!(mesh.time.len(), 29);
    assert!((mesh.time[28] - tf).abs() < 1e-15);
    let i = traj.time.iter().position(|&t| t >= tf).unwrap();
    let n = ocp.nq();
    for c in 0..2 * n {
        let (a, b) = (traj.states[i - 1][c], traj.states[i][c]);
        let (lo, hi) = (a.min(b) - 1e-9, a.max(b) + 1e-9);
        assert!(
            (lo..=hi).contains(&mesh.states[28][c]),
            "{}: {} not between {a} and {b}",
            ocp.eq.state_names()[c],
            mesh.states[28][c]
        );
    }
    // Extensors on, the others at the minimum excitation.
    let bb = ocp.bang_bang();
    for (k, iv) in bb.intervals.iter().enumerate() {
        assert_eq!(mesh.controls[5][k], if iv.is_some() { 1.0 } else { 0.01 });
    }
    // Round trip through pack/unpack.
    let v = tr.pack(&mesh.states, &mesh.controls, tf).unwrap();
    assert_eq!(&v, guess);
}

/// `integrate_on_mesh`: the bang-bang excitations integrated by the mesh's
/// own scheme. Every interval it reports converged meets its defects (the
/// constraint evaluation itself is the judge); the largest defect left is
/// the one reported; the controls and t_f are untouched; and the mesh
/// solutions converge, at first order: the excitations are the bang-bang
/// steps sampled at the nodes (linear between them), an O(h) error of the
/// input that hides the midpoint rule's second order. On 14, 28 and 56
/// intervals the state at t_f/2 moves about half as much from 28 to 56 as
/// from 14 to 28.
#[test]
fn bang_bang_guess_integrated_on_the_mesh_counts_every_interval_left() {
    // The trapezoidal rule on 8 intervals leaves intervals unsolved inside
    // the bounds as well as at them: every interval is counted once, and
    // the first one left is named.
    let mut tr = transcription(TranscriptionOptions {
        num_mesh_intervals: 8,
        scheme: Scheme::Trapezoidal,
        fiber_dynamics: FiberDynamics::Explicit,
        ..Default::default()
    });
    let (mut v, _) = tr.bang_bang_guess().unwrap();
    let report = tr.integrate_on_mesh(&mut v).unwrap();
    assert_eq!(
        report.converged + report.at_bound + report.stopped_short,
        8,
        "{report:?}"
    );
    assert!(report.converged < 8, "{report:?}");
    let mut c = vec![0.0; tr.num_constraints()];
    tr.constraints(&v, &mut c).unwrap();
    let nx = 62;
    let first = (1..=8).find(|&k| {
        c[(k - 1) * nx..k * nx]
            .iter()
            .any(|d| d.abs() > MESH_NEWTON_TOL)
    });
    assert_eq!(
        report.first_unsolved.as_ref().map(|u| u.interval),
        first,
        "{report:?}"
    );
    assert_eq!(
        report.worst_state_name,
        tr.ocp.eq.state_names()[report.worst_state]
    );
}

#[test]
fn bang_bang_guess_integrated_on_the_mesh() {
    let (_, _, guess28) = setup();
    let mut mid_states = Vec::new();
    for n in [14, 28, 56] {
        let mut tr = transcription(TranscriptionOptions {
            num_mesh_intervals: n,
            ..Default::default()
        });
        let (resampled, _) = tr.bang_bang_guess().unwrap();
        if n == 28 {
            assert_eq!(&resampled, guess28);
        }
        let mut v = resampled.clone();
        let report = tr.integrate_on_mesh(&mut v).unwrap();
        assert_eq!(report.intervals, n);
        let mut c = vec![0.0; tr.num_constraints()];
        tr.constraints(&v, &mut c).unwrap();
        let nx = 62;
        let (mut lo, mut hi) = (vec![0.0; v.len()], vec![0.0; v.len()]);
        tr.variable_bounds(&mut lo, &mut hi);
        let mut converged = 0;
        let mut worst = 0.0f64;
        let mut first_unsolved = None;
        for k in 1..=n {
            let d = c[(k - 1) * nx..k * nx]
                .iter()
                .fold(0.0f64, |a, b| a.max(b.abs()));
            converged += usize::from(d <= MESH_NEWTON_TOL);
            if d > MESH_NEWTON_TOL && first_unsolved.is_none() {
                first_unsolved = Some(k);
            }
            worst = worst.max(d);
            // An interval left unsolved has a state of its node held at a
            // bound (a fibre at its shortest on the jump): the defects have
            // no solution inside the bounds there.
            if d > MESH_NEWTON_TOL {
                let held = (0..nx).any(|i| {
                    let j = tr.state_index(k, i).unwrap();
                    v[j] == lo[j] || v[j] == hi[j]
                });
                assert!(
                    held,
                    "{n} intervals: interval {k} left at {d:e} inside the bounds"
                );
            }
        }
        assert_eq!(converged, report.converged, "{n} intervals: {report:?}");
        // Each interval left unsolved is reported as stopped at its bound.
        assert_eq!(
            (report.converged + report.at_bound, report.stopped_short),
            (n, 0),
            "{n} intervals: {report:?}"
        );
        assert_eq!(worst, report.worst_defect);
        // The first interval left unsolved is named, with the state of its
        // node held at the bound.
        match (&report.first_unsolved, first_unsolved) {
            (None, None) => {}
            (Some(u), Some(k)) => {
                assert_eq!(u.interval, k, "{n} intervals: {report:?}");
                let h = u.held.as_ref().unwrap();
                let j = tr.state_index(k, h.state).unwrap();
                assert_eq!(v[j], if h.lower { lo[j] } else { hi[j] }, "{h:?}");
                assert_eq!(h.name, tr.ocp.eq.state_names()[h.state]);
            }
            other => panic!("{n} intervals: {other:?}, {report:?}"),
        }
        // Only states move.
        for k in 0..=n {
            assert_eq!(tr.node_control(&v, k), tr.node_control(&resampled, k));
        }
        assert_eq!(tr.final_time(&v), tr.final_time(&resampled));
        assert_eq!(tr.node_state(&v, 0), tr.node_state(&resampled, 0));
        mid_states.push(tr.node_state(&v, n / 2).to_vec());
    }
    let dist = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let (coarse, fine) = (
        dist(&mid_states[0], &mid_states[1]),
        dist(&mid_states[1], &mid_states[2]),
    );
    let ratio = coarse / fine;
    assert!(
        (1.5..3.0).contains(&ratio),
        "successive differences {coarse:e}, {fine:e}: ratio {ratio}"
    );
    // A guess of the wrong size is an error, not a panic.
    let mut tr = transcription(TranscriptionOptions::default());
    assert!(tr.integrate_on_mesh(&mut [0.0; 3]).is_err());
}

/// One interval's defects and their block in node k's states, as
/// `integrate_on_mesh` evaluates them from the interval's own points, equal
/// the same rows and entries of the whole problem's `constraints` and
/// `jacobian_values` to the bit, for every scheme and both fibre-dynamics
/// forms, at a guess whose states are perturbed off the defects (each
/// interval evaluated after the whole problem at another guess); an
/// interval outside the mesh is an error.
#[test]
fn one_interval_evaluates_as_the_whole_problem() {
    let nx = 62;
    for (scheme, fiber_dynamics) in [
        (Scheme::MidpointEuler, FiberDynamics::Explicit),
        (Scheme::MidpointEuler, FiberDynamics::Implicit),
        (Scheme::Trapezoidal, FiberDynamics::Explicit),
        (Scheme::HermiteSimpson, FiberDynamics::Explicit),
        (Scheme::BackwardEuler, FiberDynamics::Explicit),
    ] {
        let n = 8;
        let options = TranscriptionOptions {
            num_mesh_intervals: n,
            scheme,
            fiber_dynamics,
            ..Default::default()
        };
        // Implicit rows have their own pattern (the fibre velocities).
        let mut tr = if fiber_dynamics == FiberDynamics::Implicit {
            Transcription::new(setup().0.clone(), options).unwrap()
        } else {
            transcription(options)
        };
        let (mut v, _) = tr.bang_bang_guess().unwrap();
        for k in 1..=n {
            for i in 0..nx {
                let j = tr.state_index(k, i).unwrap();
                v[j] *= 1.0 + 1e-3 * (((7 * k + 3 * i) % 11) as f64 - 5.0) / 5.0;
            }
        }
        let mut c = vec![0.0; tr.num_constraints()];
        tr.constraints(&v, &mut c).unwrap();
        let structure = tr.jacobian_structure();
        let mut jv = vec![0.0; structure.len()];
        tr.jacobian_values(&v, &mut jv).unwrap();
        // Every point evaluated last at another guess: the interval's
        // evaluation must cover all of its points.
        let other: Vec<f64> = v.iter().map(|x| x * (1.0 + 1e-4)).collect();
        let (mut c2, mut jv2) = (c.clone(), jv.clone());
        let mut rows = vec![0.0; nx];
        let mut block = nalgebra::DMatrix::zeros(nx, nx);
        for k in 1..=n {
            tr.jacobian_values(&other, &mut jv2).unwrap();
            tr.constraints(&other, &mut c2).unwrap();
            let worst = tr.interval_residual(&v, k, &mut rows).unwrap();
            let whole = &c[(k - 1) * nx..k * nx];
            assert_eq!(rows, whole, "{scheme:?} {fiber_dynamics:?}: interval {k}");
            assert!(worst > 0.0);
            assert_eq!(worst, whole.iter().fold(0.0f64, |a, b| a.max(b.abs())));
            tr.jacobian_values(&other, &mut jv2).unwrap();
            tr.interval_state_jacobian(&v, k, &mut block).unwrap();
            let mut expected = nalgebra::DMatrix::zeros(nx, nx);
            let mut entries = 0;
            for (&(r, col), &value) in structure.iter().zip(&jv) {
                if r / nx + 1 != k || r >= n * nx {
                    continue;
                }
                let Some(i) = (0..nx).find(|&i| tr.state_index(k, i) == Some(col)) else {
                    continue;
                };
                expected[(r % nx, i)] += value;
                entries += 1;
            }
            assert!(entries >= nx, "{scheme:?}: {entries} entries");
            assert_eq!(
                block, expected,
                "{scheme:?} {fiber_dynamics:?}: interval {k}"
            );
        }
        assert!(tr.interval_residual(&v, 0, &mut rows).is_err());
        assert!(tr.interval_residual(&v, n + 1, &mut rows).is_err());
        assert!(tr.interval_state_jacobian(&v, n + 1, &mut block).is_err());
        assert!(tr.interval_residual(&v[1..], 1, &mut rows).is_err());
        // A value the interval reads that is not finite is named.
        let j = tr.state_index(3, 0).unwrap();
        let mut bad = v.clone();
        bad[j] = f64::NAN;
        for k in [3, 4] {
            let e = tr.interval_residual(&bad, k, &mut rows).unwrap_err();
            assert!(e.to_string().contains(&tr.variable_name(j)), "{e}");
            let e = tr.interval_state_jacobian(&bad, k, &mut block).unwrap_err();
            assert!(e.to_string().contains(&tr.variable_name(j)), "{e}");
        }
        assert!(tr.interval_residual(&bad, 5, &mut rows).is_ok());
    }
}

/// Timings of the full 29-node problem (run with
/// `cargo test --release --test integration -- --ignored --nocapture transcription::timing`).
#[test]
#[ignore]
fn timing() {
    let (ocp, pattern, guess) = setup();
    let median = |mut v: Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let t = std::time::Instant::now();
    let _ = StatePattern::detect(ocp, 60, 1).unwrap();
    eprintln!(
        "pattern detection (60 samples): {:.1} ms",
        1e3 * t.elapsed().as_secs_f64()
    );
    let x = guess.to_vec();
    let mut ws = ocp.eq.workspace::<f64>();
    let mut dx = vec![0.0; ocp.nx()];
    let xs = &x[86 * 9..86 * 9 + 62];
    let us = &x[86 * 9 + 62..86 * 10];
    let f64_time = median(
        (0..500)
            .map(|_| {
                let t = std::time::Instant::now();
                ocp.state_rates(&mut ws, xs, us, &mut dx).unwrap();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    );
    eprintln!("f(x, u) in f64: {:.1} µs", 1e6 * f64_time);
    {
        use leap::scalar::Dual64;
        let mut wd = ocp.eq.workspace::<Dual64>();
        let mut xd: Vec<Dual64> = xs.iter().map(|&v| Dual64::from(v)).collect();
        let ud: Vec<Dual64> = us.iter().map(|&v| Dual64::from(v)).collect();
        let mut dxd = vec![Dual64::from(0.0); ocp.nx()];
        let t = median(
            (0..200)
                .map(|i| {
                    let j = i % 38;
                    xd[j] = Dual64::from(xs[j]).derivative();
                    let t = std::time::Instant::now();
                    ocp.state_rates(&mut wd, &xd, &ud, &mut dxd).unwrap();
                    let e = t.elapsed().as_secs_f64();
                    xd[j] = Dual64::from(xs[j]);
                    e
                })
                .collect(),
        );
        let colors = transcription(TranscriptionOptions::default())
            .jacobian_stats()
            .colors;
        eprintln!(
            "one direction with Dual64: {:.1} µs; × {colors} colours = {:.0} µs per point",
            1e6 * t,
            1e6 * t * colors as f64
        );
    }
    for (compress, once) in [(true, false), (false, false), (true, true)] {
        let mut best = [f64::INFINITY; 7];
        for _ in 0..5 {
            let t = [
                time_point_jacobian::<1>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<4>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<6>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<8>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<10>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<13>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
                time_point_jacobian::<19>(ocp, pattern, compress, once, xs, us, 20).unwrap(),
            ];
            for i in 0..7 {
                best[i] = best[i].min(t[i]);
            }
        }
        eprintln!("one Jacobian of (f, Ÿ_C, F_y) (compress {compress}, paths walked once {once}), µs for W = 1, 4, 6, 8, 10, 13, 19 lanes: {:?}", best.map(|v| (v * 1e6).round()));
    }
    {
        let mut tr = transcription(TranscriptionOptions::default());
        let mut c = vec![0.0; tr.num_constraints()];
        tr.constraints(&x, &mut c).unwrap();
        let (y, yd, j) = tr.jump_objective(&x);
        eprintln!(
            "bang-bang guess: t_f {:.4} s, Y_C {y:.4} m, Ẏ_C {yd:.4} m/s, J {j:.4} m (jump height {:.4} m), max |defect| {:.3e}, no-countermovement rows {:?}, lift-off row {:.3e}",
            tr.final_time(&x),
            j - ocp.standing_com_height,
            c[tr.defect_rows()].iter().fold(0.0f64, |m, d| m.max(d.abs())),
            c[tr.no_countermovement_rows()].iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
            c[tr.liftoff_row()]
        );
        let mut rows: Vec<usize> = tr.defect_rows().collect();
        rows.sort_by(|&a, &b| c[b].abs().total_cmp(&c[a].abs()));
        for &r in &rows[..6] {
            eprintln!("  {}: {:.3e}", tr.constraint_name(r), c[r]);
        }
        let by_kind = |lo: usize, hi: usize| {
            tr.defect_rows()
                .filter(|r| (lo..hi).contains(&(r % 62)))
                .map(|r| c[r].abs())
                .fold(0.0f64, f64::max)
        };
        eprintln!(
            "  max |defect| of q {:.2e}, q̇ {:.2e}, l^M {:.2e}, a {:.2e}",
            by_kind(0, 7),
            by_kind(7, 14),
            by_kind(14, 38),
            by_kind(38, 62)
        );
    }
    {
        let t = time_hessian_passes(ocp, pattern, xs, us, 20).unwrap();
        eprintln!(
            "second-order passes at one point: q × (q, q̇) {:.2} ms, q̇ × q̇ with its first-order paths {:.2} ms, all passes {:.2} ms",
            1e3 * t[0],
            1e3 * t[1],
            1e3 * t[2]
        );
    }
    for scheme in [
        Scheme::MidpointEuler,
        Scheme::Trapezoidal,
        Scheme::HermiteSimpson,
    ] {
        for threads in [1, 2] {
            let mut tr = transcription(TranscriptionOptions {
                threads,
                scheme,
                ..Default::default()
            });
            let els = tr.elements();
            let lambda: Vec<f64> = (0..tr.num_constraints())
                .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
                .collect();
            let mut hs: Vec<Vec<f64>> = els
                .iter()
                .map(|e| vec![0.0; e.variables.len().pow(2)])
                .collect();
            let mut xs = x.clone();
            let (mut th, mut ta) = (vec![], vec![]);
            for rep in 0..10 {
                // A new x each sweep (the point derivatives are cached per x).
                xs[0] = x[0] + 1e-9 * rep as f64;
                let t = std::time::Instant::now();
                for (e, h) in hs.iter_mut().enumerate() {
                    tr.element_hessian(&xs, e, 1.0, &lambda, h).unwrap();
                }
                th.push(t.elapsed().as_secs_f64());
                // The same x again: assembly from the cache only.
                let t = std::time::Instant::now();
                for (e, h) in hs.iter_mut().enumerate() {
                    tr.element_hessian(&xs, e, 1.0, &lambda, h).unwrap();
                }
                ta.push(t.elapsed().as_secs_f64());
            }
            eprintln!(
                "{scheme:?}, {threads} thread(s): all {} element Hessians {:.1} ms (of which assembling the blocks {:.1} ms; median of 10)",
                els.len(),
                1e3 * median(th),
                1e3 * median(ta)
            );
        }
    }
    for scheme in [
        Scheme::MidpointEuler,
        Scheme::Trapezoidal,
        Scheme::HermiteSimpson,
    ] {
        for threads in [1, 2] {
            let mut tr = transcription(TranscriptionOptions {
                threads,
                scheme,
                ..Default::default()
            });
            let mut c = vec![0.0; tr.num_constraints()];
            let mut jv = vec![0.0; tr.jacobian_nnz()];
            let (mut tc, mut tj) = (vec![], vec![]);
            for _ in 0..40 {
                let t = std::time::Instant::now();
                tr.constraints(&x, &mut c).unwrap();
                tc.push(t.elapsed().as_secs_f64());
                let t = std::time::Instant::now();
                tr.jacobian_values(&x, &mut jv).unwrap();
                tj.push(t.elapsed().as_secs_f64());
            }
            let st = tr.jacobian_stats();
            eprintln!("{scheme:?}, {threads} thread(s): constraints {:.3} ms, Jacobian {:.3} ms (median of 40; {} non-zeros, {} per defect block)", 1e3 * median(tc), 1e3 * median(tj), st.nnz, st.nnz_interval);
        }
    }
}

/// Uniform multipliers in [-1, 1) (SplitMix64).
fn random_multipliers(m: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..m)
        .map(|_| {
            s = s.wrapping_add(0x9E3779B97F4A7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

/// Every element Hessian at `x`: finite and exactly symmetric, and the
/// same whether computed element by element or all at once (the point
/// derivatives refreshed once), also through the SQP's variable scaling.
fn element_hessians_symmetric(tr: &mut Transcription, x: &[f64], lambda: &[f64]) {
    let elements = tr.elements();
    let fresh = |els: &[leap::nlp::Element]| -> Vec<Vec<f64>> {
        els.iter()
            .map(|el| vec![f64::NAN; el.variables.len().pow(2)])
            .collect()
    };
    let mut all = fresh(&elements);
    tr.element_hessians(x, 0.7, lambda, &mut all).unwrap();
    for (e, el) in elements.iter().enumerate() {
        let k = el.variables.len();
        let mut h = vec![f64::NAN; k * k];
        tr.element_hessian(x, e, 0.7, lambda, &mut h).unwrap();
        assert_eq!(h, all[e], "element {e}: one by one and all at once");
        for a in 0..k {
            for b in 0..k {
                assert!(h[a * k + b].is_finite(), "element {e} ({a}, {b})");
                assert_eq!(h[a * k + b], h[b * k + a], "element {e} ({a}, {b})");
            }
        }
    }
    let mut scaled = leap::nlp::ScaledVariables::from_bounds(tr);
    let xs = scaled.scale_point(x);
    let mut all = fresh(&elements);
    scaled.element_hessians(&xs, 0.7, lambda, &mut all).unwrap();
    for (e, el) in elements.iter().enumerate() {
        let mut h = vec![f64::NAN; el.variables.len().pow(2)];
        scaled.element_hessian(&xs, e, 0.7, lambda, &mut h).unwrap();
        assert_eq!(h, all[e], "scaled element {e}: one by one and all at once");
    }
}

/// The exact element Hessians (midpoint Euler and trapezoidal) against
/// central differences of the Lagrangian gradient ∇f + Jᵀλ, with random λ.
///
/// Tolerances. At a perturbed point (every activation off its bound, the
/// feet in contact) `check_derivatives` with step 1e-6 agrees to ~1e-4
/// (relative to max(1, |entry|)): the differences' roundoff is
/// ε·|∇L terms|/step ≈ 1e-16·1e6/1e-6 ≈ 1e-4 on O(1) entries, since the
/// Lagrangian gradient sums Jacobian entries of 1e5-1e6 (tendon and contact
/// stiffness) — the worst entries are ∂²/∂l^M∂q of size 0.5 with the two
/// steps 1e-6 and 1e-7 disagreeing with each other by 1e-2, while the
/// exact value agrees with the better step. With the trapezoidal nodes a
/// single step is noisier still (its Jacobian check there: 9e-4, the
/// Hessian 5e-3), so `check_derivatives` is held to 1e-2 and the best of
/// the steps 1e-6 and 1e-7 (central) and Richardson's extrapolation of
/// central differences with steps 1e-5 and 2e-5 (truncation O(h⁴), for
/// where the activation switch's third derivatives make 1e-6 too wide:
/// at b = 200 the small steps alone leave 6e-4 on iliacus's ∂²/∂l^M∂q,
/// Richardson 3.5e-5) to 5e-4; a wrong term (a missing 1/2, a sign) is
/// off by O(1).
/// At the bang-bang guess the activations and excitations of the inactive
/// muscles sit exactly on their minimum 0.01 (a kink of the model at
/// a = a_min, where the exact derivative is one branch's and a central
/// difference the mean of both) and the final node at contact onset
/// (F ∝ depth^{3/2}, curvature ∝ depth^{-1/2} changing within a step of
/// 1e-6). There each entry is compared with the best of central
/// differences (steps 1e-6, 1e-7) and one-sided ones (1e-7), to 1e-2: the
/// one-sided truncation error is O(step·f''') and the activation
/// dynamics' curvature near a_min is steep (measured 1e-3 on ∂²ȧ/∂a²).
/// That catches wrong terms (off by O(1)); the perturbed point is the
/// precise check.
#[test]
fn element_hessians_match_finite_differences() {
    for scheme in [
        Scheme::MidpointEuler,
        Scheme::Trapezoidal,
        Scheme::BackwardEuler,
        Scheme::HermiteSimpson,
    ] {
        let mut tr = transcription(TranscriptionOptions {
            num_mesh_intervals: 8,
            scheme,
            ..Default::default()
        });
        assert!(tr.has_hessian());
        let (guess, _) = tr.bang_bang_guess().unwrap();
        let m = tr.num_constraints();
        // Hermite–Simpson's centre leaves the model's range if perturbed
        // fibres move fast (see `jacobian_matches_finite_differences_other_schemes`).
        let amplitude = if scheme == Scheme::HermiteSimpson {
            1e-4
        } else {
            0.02
        };
        let xp = perturbed_by(&tr, &guess, 7, amplitude);
        let lambda = random_multipliers(m, 11);
        element_hessians_symmetric(&mut tr, &xp, &lambda);
        let rep = leap::nlp::check_derivatives(&mut tr, &xp, &lambda, 1e-6).unwrap();
        eprintln!("{scheme:?} perturbed point: {rep:?}");
        let err = rep.hessian.unwrap();
        // Hermite–Simpson's single step is noise: its rows compose f at
        // the centre with f at the nodes (the Jacobian itself checks to
        // 0.18 at this step); the best of the steps below is its check.
        if scheme != Scheme::HermiteSimpson {
            assert!(err < 1e-2, "{scheme:?}: Hessian error {err:.3e}");
        }
        let rep = hessian_fd_report(&mut tr, &xp, &lambda, 1e-6);
        eprintln!(
            "{scheme:?} perturbed point, best of steps: {:?}",
            rep.iter().take(3).collect::<Vec<_>>()
        );
        // Hermite–Simpson: measured ≤ 5.1e-3 (two points), on entries
        // whose exact value is 0 (pelvis_tx: the model is invariant to it)
        // and whose two central differences disagree in sign: roundoff.
        let bound = if scheme == Scheme::HermiteSimpson {
            2e-2
        } else {
            5e-4
        };
        assert!(
            rep.first().is_none_or(|r| r.0 < bound),
            "{scheme:?}: {:?}",
            rep.first()
        );
        let lambda = random_multipliers(m, 12);
        // Hermite–Simpson: at the guess the inactive muscles' centre
        // activations sit on the model's clamp at a_min = 0.01 (both nodes
        // there, ȧ = 0), a kink in every direction that moves a node's ȧ,
        // which the differences straddle: a second perturbed point instead,
        // held to the first one's bound.
        let (x2, what, bound2) = if scheme == Scheme::HermiteSimpson {
            (
                perturbed_by(&tr, &guess, 8, amplitude),
                "second perturbed point",
                bound,
            )
        } else {
            (guess, "bang-bang guess", 1e-2)
        };
        element_hessians_symmetric(&mut tr, &x2, &lambda);
        let rep = hessian_fd_report(&mut tr, &x2, &lambda, 1e-6);
        eprintln!(
            "{scheme:?} {what}: {} entries off by > 1e-7, worst {:?}",
            rep.len(),
            rep.first()
        );
        assert!(
            rep.first().is_none_or(|r| r.0 < bound2),
            "{scheme:?} {what}: {:?}",
            rep.first()
        );
    }
}

/// Hessian entries off by more than 1e-7 (relative to max(1, |fd|))
/// from differences of the Lagrangian gradient (the best of central with
/// steps `step` and `step`/10, one-sided with `step`/10, and Richardson's
/// extrapolation (4·D(h) − D(2h))/3 of central differences with h =
/// 10·`step`, whose truncation error is O(h⁴) where a central difference's
/// is O(h²): where the activation switch is sharp, the third derivatives
/// are large and neither small step is both free of truncation and of
/// roundoff), worst first: (error, entry, exact, central fd, central fd/10,
/// whether the two central steps agree to 1e-6).
#[allow(clippy::type_complexity)]
fn hessian_fd_report(
    tr: &mut Transcription,
    x: &[f64],
    lambda: &[f64],
    step: f64,
) -> Vec<(f64, String, f64, f64, f64, bool)> {
    let n = tr.num_variables();
    let hm = leap::nlp::assemble_hessian(tr, x, 1.0, lambda).unwrap();
    let pattern = tr.jacobian_structure();
    let lag = |tr: &mut Transcription, x: &[f64]| {
        let mut g = vec![0.0; n];
        tr.gradient(x, &mut g).unwrap();
        let mut jv = vec![0.0; pattern.len()];
        tr.jacobian_values(x, &mut jv).unwrap();
        for (k, &(i, j)) in pattern.iter().enumerate() {
            g[j] += lambda[i] * jv[k];
        }
        g
    };
    let mut out = Vec::new();
    let mut xp = x.to_vec();
    let g0 = lag(tr, x);
    for j in 0..n {
        let mut at = |tr: &mut Transcription, s: f64| {
            xp[j] = x[j] + s;
            let g = lag(tr, &xp);
            xp[j] = x[j];
            g
        };
        let s = step * x[j].abs().max(1.0);
        let (gp, gm) = (at(tr, s), at(tr, -s));
        let (gp2, gm2) = (at(tr, 0.1 * s), at(tr, -0.1 * s));
        // The wider steps only for the columns the small ones leave in doubt.
        let mut wide: Option<[Vec<f64>; 4]> = None;
        for i in 0..n {
            let e = hm[i * n + j];
            let d1 = (gp[i] - gm[i]) / (2.0 * s);
            let d2 = (gp2[i] - gm2[i]) / (0.2 * s);
            // One-sided (a kink of f at x: the exact value is one branch's).
            let fwd = (gp2[i] - g0[i]) / (0.1 * s);
            let bwd = (g0[i] - gm2[i]) / (0.1 * s);
            let best = |ds: &[f64]| {
                ds.iter()
                    .map(|d| (e - d).abs() / d.abs().max(1.0))
                    .fold(f64::INFINITY, f64::min)
            };
            let mut err = best(&[d1, d2, fwd, bwd]);
            if err > 1e-7 {
                let [p10, m10, p20, m20] =
                    wide.get_or_insert_with(|| [10.0, -10.0, 20.0, -20.0].map(|k| at(tr, k * s)));
                let richardson =
                    (4.0 * (p10[i] - m10[i]) / (20.0 * s) - (p20[i] - m20[i]) / (40.0 * s)) / 3.0;
                err = err.min(best(&[richardson]));
            }
            if err > 1e-7 {
                let smooth = (d1 - d2).abs() / d1.abs().max(1.0) < 1e-6;
                out.push((
                    err,
                    format!("{} / {}", tr.variable_name(i), tr.variable_name(j)),
                    e,
                    d1,
                    d2,
                    smooth,
                ));
            }
        }
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out
}

#[test]
#[ignore]
fn hessian_diagnostic() {
    let scheme = if std::env::var("TRAP").is_ok() {
        Scheme::Trapezoidal
    } else {
        Scheme::MidpointEuler
    };
    let mut tr = transcription(TranscriptionOptions {
        num_mesh_intervals: 8,
        scheme,
        ..Default::default()
    });
    let (guess, _) = tr.bang_bang_guess().unwrap();
    let x = if std::env::var("PERTURB").is_ok() {
        perturbed(&tr, &guess, 7)
    } else {
        guess
    };
    let lambda = random_multipliers(tr.num_constraints(), 11);
    let rep = hessian_fd_report(&mut tr, &x, &lambda, 1e-6);
    eprintln!("{} entries > 1e-6", rep.len());
    for r in rep.iter().take(40) {
        eprintln!(
            "{:.2e} {}: exact {:.6e} fd {:.6e} fd/10 {:.6e}",
            r.0, r.1, r.2, r.3, r.4
        );
    }
}

/// Implicit fibre dynamics, 8 intervals (own pattern: the force balances
/// depend on the fibre velocities).
fn implicit_transcription() -> Transcription {
    let (ocp, _, _) = setup();
    Transcription::new(
        ocp.clone(),
        TranscriptionOptions {
            num_mesh_intervals: 8,
            fiber_dynamics: FiberDynamics::Implicit,
            ..Default::default()
        },
    )
    .unwrap()
}

/// The force-balance rows' Jacobian (node means, the fibre velocity
/// (l^M_k − l^M_{k−1})/h and its t_f dependence) and element Hessians
/// (chain rule through v̄, with its second derivatives in t_f) against
/// finite differences, held to the explicit form's tolerances (see
/// `jacobian_matches_finite_differences_midpoint` and
/// `element_hessians_match_finite_differences`).
#[test]
fn implicit_fiber_dynamics_derivatives_match_finite_differences() {
    let mut tr = implicit_transcription();
    assert!(tr.has_hessian());
    let (guess, _) = tr.bang_bang_guess().unwrap();
    let xp = perturbed(&tr, &guess, 7);
    let r = fd_check(&mut tr, &xp);
    eprintln!("implicit, perturbed guess: {} entries, worst {:.2e} ({}), kinks {}, refined {}, row-scaled {}, outside {:.2e} ({})", r.entries, r.worst, r.worst_at, r.kinks, r.refined, r.row_scaled, r.outside, r.outside_at);
    assert!(r.worst <= 1e-6, "{}", r.worst_at);
    assert!(r.outside <= 1e-7, "{}", r.outside_at);
    assert!(r.kinks <= r.entries / 1000, "{} kinks", r.kinks);
    let lambda = random_multipliers(tr.num_constraints(), 11);
    element_hessians_symmetric(&mut tr, &xp, &lambda);
    let rep = hessian_fd_report(&mut tr, &xp, &lambda, 1e-6);
    eprintln!("implicit perturbed point, best of steps: {:?}", rep.first());
    assert!(rep.first().is_none_or(|r| r.0 < 5e-4), "{:?}", rep.first());
}

/// The two forms have the same solutions: where a fibre-length defect of
/// the explicit form vanishes (l^M at node k solved for by the secant
/// method, everything else at the guess), the implicit form's force balance
/// vanishes too, and every other row is the same in both.
#[test]
fn implicit_and_explicit_fiber_rows_vanish_together() {
    let mut imp = implicit_transcription();
    let mut exp = transcription(TranscriptionOptions {
        num_mesh_intervals: 8,
        ..Default::default()
    });
    let (guess, _) = exp.bang_bang_guess().unwrap();
    let x = perturbed(&exp, &guess, 3);
    let m = exp.num_constraints();
    let (mut ce, mut ci) = (vec![0.0; m], vec![0.0; m]);
    exp.constraints(&x, &mut ce).unwrap();
    imp.constraints(&x, &mut ci).unwrap();
    let nx = exp.ocp.nx();
    let lm0 = 2 * exp.ocp.nq();
    for i in 0..m {
        if !imp.is_balance_row(i % nx) || i >= exp.num_intervals() * nx {
            assert_eq!(ce[i], ci[i], "{}", exp.constraint_name(i));
        }
    }
    let mut checked = 0;
    for k in [1, 4, 8] {
        for mi in [0, 5, 15, 21] {
            let r = lm0 + mi;
            let row = (k - 1) * nx + r;
            let col = exp.state_index(k, r).unwrap();
            let resid = |tr: &mut Transcription, v: f64| {
                let mut y = x.clone();
                y[col] = v;
                let mut c = vec![0.0; m];
                tr.constraints(&y, &mut c).unwrap();
                c[row]
            };
            // Secant on the explicit defect in l^M_k.
            let (mut a, mut b) = (x[col], x[col] * (1.0 + 1e-3));
            let (mut fa, mut fb) = (resid(&mut exp, a), resid(&mut exp, b));
            for _ in 0..50 {
                if fb.abs() < 1e-15 || fa == fb {
                    break;
                }
                let c = b - fb * (b - a) / (fb - fa);
                (a, fa) = (b, fb);
                (b, fb) = (c, resid(&mut exp, c));
            }
            assert!(fb.abs() < 1e-13, "explicit defect {fb} not solved");
            let balance = resid(&mut imp, b);
            let away = resid(&mut imp, x[col]);
            eprintln!(
                "interval {k}, {}: balance {balance:.2e} at the root, {away:.2e} at the guess",
                imp.constraint_name(row)
            );
            // The explicit root is good to ~1e-15 m; the balance's slope in
            // l^M is at most ~1e5 F0/m (tendon stiffness) and h/(v_max l_o).
            assert!(
                balance.abs() < 1e-8,
                "{}: {balance}",
                imp.constraint_name(row)
            );
            assert!(away.abs() > 1e3 * balance.abs().max(1e-12));
            checked += 1;
        }
    }
    assert_eq!(checked, 12);
}

/// `Backend::Simbody` (`leap solve --backend simbody`), the cross-check path
/// of the derivatives, through `leap crosscheck --jacobian`
/// (`crosscheck::jacobian`): every point evaluated by Simbody's multibody
/// system (the same force laws in a Simbody force element), the Jacobian by
/// central differences over the same colouring.
/// - Its rows agree with the Rust-native ones to the agreement of the two
///   dynamics (`leap crosscheck` asserts ẋ within 1e-9).
/// - Its Jacobian agrees with the exact dual-number one to 1e-6 of each
///   row's largest entry, as `jacobian_matches_finite_differences_*` asks of
///   Rust-native differences, at points off the activation switch (perturbed
///   guesses; where a = u = a_min, as at the bang-bang guess, the one-sided
///   derivatives differ).
/// - Simbody's differences over every column, not coloured, find nothing
///   outside the pattern that the Rust-native samples detected.
/// - Entries beyond 1e-6 must be kinks (`JacobianPoint::entries_at_kinks`):
///   backward Euler evaluates the dynamics at the nodes, where a fibre on
///   its clamp or a slack tendon makes the derivative jump.
#[test]
fn simbody_backend_matches_rust_native_rows_and_jacobian() {
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    for (fiber_dynamics, scheme, n) in [
        (FiberDynamics::Explicit, Scheme::MidpointEuler, 28),
        (FiberDynamics::Implicit, Scheme::MidpointEuler, 28),
        (FiberDynamics::Explicit, Scheme::HermiteSimpson, 10),
        (FiberDynamics::Explicit, Scheme::BackwardEuler, 10),
    ] {
        let options = TranscriptionOptions {
            num_mesh_intervals: n,
            scheme,
            fiber_dynamics,
            ..Default::default()
        };
        let r = leap::crosscheck::jacobian(&model, options, 2, 5).unwrap();
        eprintln!("{}", r.table());
        let what = format!("{fiber_dynamics:?} {scheme:?}");
        assert_eq!(r.points.len(), 3);
        for p in &r.points {
            assert!(p.rows <= 1e-9, "{what}, {}: {}", p.point, p.rows_at);
            if p.checked {
                assert!(
                    p.jacobian <= 1e-6 || p.entries_at_kinks == p.entries_beyond,
                    "{what}, {}: {}",
                    p.point,
                    p.jacobian_at
                );
            }
        }
        // The guess's muscles that are off sit on the activation switch.
        assert!(!r.points[0].checked && r.points[0].entries_beyond > 0);
        assert!(
            r.outside_pattern <= 1e-7,
            "{what}: {}",
            r.outside_pattern_at
        );
        assert!(r.passed, "{what}");
    }
    // Differences are the Simbody backend's.
    let mut tr = transcription(TranscriptionOptions::default());
    assert!(tr
        .set_differences(Differences::Forward { step: 1e-8 })
        .is_err());
    // The one-sided differences the kink check uses: their mean, the
    // central difference of the same step, is within 1e-6 of each row's
    // largest exact entry (the tolerance above).
    let (_, _, guess) = setup();
    let x = perturbed_by(&tr, guess, 5, 1e-3);
    let mut exact = vec![0.0; tr.jacobian_nnz()];
    tr.jacobian_values(&x, &mut exact).unwrap();
    let mut sb = transcription(TranscriptionOptions {
        backend: Backend::Simbody,
        ..Default::default()
    });
    let mut sides = Vec::new();
    for d in [
        Differences::Forward { step: 1e-8 },
        Differences::Backward { step: 1e-8 },
    ] {
        sb.set_differences(d).unwrap();
        let mut one_sided = vec![0.0; exact.len()];
        sb.jacobian_values(&x, &mut one_sided).unwrap();
        sides.push(one_sided);
    }
    let structure = tr.jacobian_structure();
    let mut scale = vec![1.0f64; tr.num_constraints()];
    for (&(i, _), v) in structure.iter().zip(&exact) {
        scale[i] = scale[i].max(v.abs());
    }
    let (mut mean_worst, mut beyond) = (0.0f64, 0);
    for (e, &(i, _)) in structure.iter().enumerate() {
        let (f, b) = (sides[0][e], sides[1][e]);
        let m = ((f + b) / 2.0 - exact[e]).abs() / scale[i];
        mean_worst = mean_worst.max(m);
        beyond += usize::from(m.is_nan() || m > 1e-6);
    }
    eprintln!("one-sided differences: mean within {mean_worst:.1e} of the exact entry, {beyond} of {} beyond 1e-6", exact.len());
    // Rounding at step 1e-8 (ε·|f|/h): at most one entry in a thousand.
    assert!(
        mean_worst.is_finite() && beyond <= exact.len() / 1000,
        "{beyond} entries, worst {mean_worst}"
    );
    assert!(sb
        .set_differences(Differences::Central { step: 0.0 })
        .is_err());
}

/// The sparsity of the state equation does not depend on how sharply the
/// optimizer's activation switch is smoothed: with b = 1000 (the largest
/// `activation_dynamics_smoothing` a study may give) the pattern equals
/// the default's, for both fibre dynamics, and builds a transcription.
/// num-dual's tanh of a dual number overflowed there (NaN from |b·(u − a)|
/// ≈ 355), which marked spurious dependencies at the sample states, one of
/// them a fibre velocity input that the transcription mapped onto the next
/// node's columns ("Jacobian entry (1730, 2409) is outside 1772×2409").
#[test]
fn the_pattern_does_not_depend_on_the_activation_smoothing() {
    let model = leap::model::Model::from_file("models/jumper_reduced.json").unwrap();
    let opts = TranscriptionOptions::default();
    for fiber_dynamics in [FiberDynamics::Explicit, FiberDynamics::Implicit] {
        let pattern = |b: f64| {
            let ocp = Arc::new(
                JumpOcp::new(
                    &model,
                    OcpOptions {
                        activation_smoothing: Some(b),
                        ..OcpOptions::default()
                    },
                )
                .unwrap(),
            );
            let p = StatePattern::detect_for(
                &ocp,
                fiber_dynamics,
                opts.pattern_samples,
                opts.pattern_seed,
            )
            .unwrap();
            (ocp, p)
        };
        let (_, default) = pattern(50.0);
        let (ocp, sharp) = pattern(1000.0);
        assert_eq!(sharp.rows, default.rows, "{fiber_dynamics:?}");
        Transcription::with_pattern(
            ocp,
            TranscriptionOptions {
                fiber_dynamics,
                ..opts
            },
            sharp,
        )
        .unwrap();
    }
}
