//! The simulation job without the CLI: `cargo run --release -p swarmpose-sim --example
//! simulate -- [--quick] [--structured] [OUT_DIR]`.

use std::path::PathBuf;
use std::process::ExitCode;

use swarmpose_sim::{Experiment, SimOptions, default_estimators, simulate};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let mut opts = SimOptions::default();
    if quick {
        opts.experiment = Experiment::quick();
        opts.out_dir = PathBuf::from("out/simulate-quick");
    }
    if args.iter().any(|a| a == "--structured") {
        opts.experiment.mode = swarmpose_sim::OutlierMode::Structured;
    }
    if let Some(dir) = args.iter().find(|a| !a.starts_with("--")) {
        opts.out_dir = PathBuf::from(dir);
    }
    match simulate(&opts, &default_estimators()) {
        Ok(outcome) => {
            print!("{}", outcome.console);
            for f in &outcome.files {
                println!("wrote {}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("simulate: error: {e}");
            ExitCode::FAILURE
        }
    }
}
