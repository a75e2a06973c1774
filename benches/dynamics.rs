//! `cargo bench --bench dynamics`: time per q̈ evaluation of the jumper
//! skeleton, Rust-native against Simbody, as a table (same as
//! `leap bench dynamics`).

fn main() {
    // cargo bench passes flags such as --bench; the model is fixed.
    let model = match leap::model::Model::from_file("models/jumper.json") {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    match leap::bench::dynamics(&model) {
        Ok(report) => println!("{}", report.table()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
