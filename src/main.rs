//! The `leap` command line.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "leap", version, about = "Predict human movement by optimal control (OpenSim-compatible models).")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compare the Rust-native dynamics with Simbody at random states.
    Crosscheck {
        /// Model file (JSON).
        #[arg(long, default_value = "models/jumper.json")]
        model: PathBuf,
        /// Number of random states.
        #[arg(long, default_value_t = 100)]
        samples: usize,
        /// Seed of the random states.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Benchmarks that print tables (medians of repeated batches).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Time per q̈ evaluation of a skeleton, Rust-native against Simbody.
    Dynamics {
        #[arg(long, default_value = "models/jumper.json")]
        model: PathBuf,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Crosscheck { model, samples, seed, json } => {
            if samples == 0 {
                anyhow::bail!("--samples must be at least 1");
            }
            let m = leap::model::Model::from_file(&model)?;
            let report = leap::crosscheck::run(&m, samples, seed)
                .with_context(|| format!("cross-check of {}", model.display()))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                println!("{}", report.table());
            }
            Ok(if report.passed { ExitCode::SUCCESS } else { ExitCode::from(1) })
        }
        Command::Bench { which: BenchCommand::Dynamics { model, json } } => {
            let m = leap::model::Model::from_file(&model)?;
            let report = leap::bench::dynamics(&m)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                println!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}
