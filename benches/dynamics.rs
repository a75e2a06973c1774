//! `cargo bench --bench dynamics`: the tables of `leap bench dynamics`,
//! `leap bench state-equation` and `leap bench integrators` for the jumper.

fn main() {
    let model = match leap::model::Model::from_file("models/jumper.json") {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    match leap::bench::dynamics(&model) {
        Ok(report) => println!("{}\n", report.table()),
        Err(e) => eprintln!("error: {e}"),
    }
    match leap::bench::state_equation(&model) {
        Ok(report) => println!("{}\n", report.table()),
        Err(e) => eprintln!("error: {e}"),
    }
    let cases = [
        ("RungeKuttaMerson", 1e-5),
        ("RungeKuttaFeldberg", 1e-5),
        ("CPodes", 1e-5),
        ("DormandPrince", 1e-5),
    ];
    match leap::bench::integrators(&model, &cases) {
        Ok(rows) => println!("{}", leap::bench::integrator_table(&rows)),
        Err(e) => eprintln!("error: {e}"),
    }
}
