//! Benchmarks that print tables: medians over repeated batches, measured in
//! one run so ratios compare like with like.

use crate::model::Model;
use crate::multibody::Multibody;
use crate::simbody::SimbodyModel;
use serde::Serialize;
use std::hint::black_box;
use std::time::Instant;

/// One timed row.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    pub system: String,
    pub backend: String,
    pub what: String,
    pub nq: usize,
    pub median_ns: f64,
    pub min_ns: f64,
    pub max_ns: f64,
    pub batches: usize,
    pub calls_per_batch: usize,
}

/// The dynamics benchmark's results.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicsReport {
    pub model: String,
    pub rows: Vec<BenchRow>,
    /// Simbody median / Rust-native median, per system.
    pub speedup: Vec<(String, f64)>,
}

/// Median, min and max nanoseconds per call over `batches` batches.
pub fn time_per_call(batches: usize, calls: usize, mut f: impl FnMut(usize)) -> (f64, f64, f64) {
    // Warm up.
    for i in 0..calls.min(1000) {
        f(i);
    }
    let mut per_call: Vec<f64> = (0..batches)
        .map(|_| {
            let t0 = Instant::now();
            for i in 0..calls {
                f(i);
            }
            t0.elapsed().as_nanos() as f64 / calls as f64
        })
        .collect();
    per_call.sort_by(|a, b| a.total_cmp(b));
    (per_call[per_call.len() / 2], per_call[0], per_call[per_call.len() - 1])
}

/// Time per q̈ evaluation (set q and q̇, apply generalized forces, solve for
/// q̈) of the model's full and symmetric systems, Rust-native against Simbody.
pub fn dynamics(model: &Model) -> Result<DynamicsReport, crate::crosscheck::CrosscheckError> {
    let mut rows = Vec::new();
    let mut speedup = Vec::new();
    let mut systems = vec![("full", model.system(false)?)];
    if !model.symmetry.is_empty() {
        systems.push(("symmetric", model.system(true)?));
    }
    let pose = model.poses.get("squat").cloned().unwrap_or_else(|| model.coordinates.iter().map(|c| c.default_value).collect());
    for (label, sys) in systems {
        let n = sys.nq();
        let q0 = sys.q_from_model(&pose);
        // A small set of distinct states, cycled, so no cache short-cuts a call.
        let states: Vec<(Vec<f64>, Vec<f64>)> = (0..16)
            .map(|k| {
                let s = 0.01 * k as f64;
                (q0.iter().enumerate().map(|(i, q)| q + s * ((i + 1) as f64).sin()).collect(), (0..n).map(|i| s * (i as f64 - 2.0)).collect())
            })
            .collect();
        let tau: Vec<f64> = (0..n).map(|i| 10.0 * (i as f64).cos()).collect();

        let mb = Multibody::new(model, &sys);
        let mut ws = mb.workspace::<f64>();
        let mut qdd = vec![0.0; n];
        let mut failed = false;
        let (med_r, min_r, max_r) = time_per_call(31, 20_000, |i| {
            let (q, u) = &states[i % states.len()];
            mb.set_state(&mut ws, q, u);
            failed |= mb.forward_dynamics(&mut ws, black_box(&tau), &mut qdd).is_err();
            black_box(&qdd);
        });
        if failed {
            return Err(crate::multibody::SingularMassMatrix { pivot: 0, value: f64::NAN }.into());
        }
        rows.push(BenchRow {
            system: label.into(),
            backend: "rust-native".into(),
            what: "set q, q̇; q̈ = M⁻¹(τ − b)".into(),
            nq: n,
            median_ns: med_r,
            min_ns: min_r,
            max_ns: max_r,
            batches: 31,
            calls_per_batch: 20_000,
        });

        let mut sb = SimbodyModel::new(model, &sys)?;
        sb.set_state(0.0, &states[0].0, &states[0].1)?;
        sb.set_applied_forces(&tau, &[])?;
        let mut err = None;
        let (med_s, min_s, max_s) = time_per_call(15, 2_000, |i| {
            let (q, u) = &states[i % states.len()];
            if let Err(e) = sb.set_state(0.0, q, u).and_then(|_| sb.accelerations(&mut qdd)) {
                err = Some(e);
            }
            black_box(&qdd);
        });
        if let Some(e) = err {
            return Err(e.into());
        }
        rows.push(BenchRow {
            system: label.into(),
            backend: "simbody".into(),
            what: "set q, q̇; realize(Acceleration)".into(),
            nq: n,
            median_ns: med_s,
            min_ns: min_s,
            max_ns: max_s,
            batches: 15,
            calls_per_batch: 2_000,
        });
        speedup.push((label.to_string(), med_s / med_r));
    }
    Ok(DynamicsReport { model: model.file.display().to_string(), rows, speedup })
}

impl DynamicsReport {
    /// A table a person can read.
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header(["system", "nq", "backend", "evaluation", "median ns/call", "min", "max", "batches × calls"]);
        for r in &self.rows {
            t.add_row([
                r.system.clone(),
                r.nq.to_string(),
                r.backend.clone(),
                r.what.clone(),
                format!("{:.0}", r.median_ns),
                format!("{:.0}", r.min_ns),
                format!("{:.0}", r.max_ns),
                format!("{} × {}", r.batches, r.calls_per_batch),
            ]);
        }
        let ratios: Vec<String> = self.speedup.iter().map(|(s, r)| format!("{s}: Rust-native {r:.1}× faster than Simbody")).collect();
        format!("q̈ evaluation, {}\n{t}\n{}", self.model, ratios.join("\n"))
    }
}
