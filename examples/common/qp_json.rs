//! Reading the QPs the SQP writes (clarabel JSON, `qp_dump_dir`), shared
//! by the examples that replay them.

/// A sparse matrix (`P` or `A`) of a clarabel JSON file.
pub fn csc(
    v: &serde_json::Value,
) -> Result<clarabel::algebra::CscMatrix<f64>, Box<dyn std::error::Error>> {
    let us = |k: &str| -> Result<Vec<usize>, Box<dyn std::error::Error>> {
        Ok(serde_json::from_value(v[k].clone())?)
    };
    Ok(clarabel::algebra::CscMatrix::new(
        serde_json::from_value(v["m"].clone())?,
        serde_json::from_value(v["n"].clone())?,
        us("colptr")?,
        us("rowval")?,
        serde_json::from_value(v["nzval"].clone())?,
    ))
}
