//! Stereo-noise scenarios as files in the peers' suite format, so `swarmpose bench` and
//! the peers' harness run the same scenes:
//! `cargo run --release -p swarmpose-sim --example export_stereo -- OUT_DIR [RUNS] [FIRST_SEED]`.
//!
//! Street scenes (`StereoSpec::street`, 600 correspondences) at 90, 95 and 97 % wrong
//! matches, `RUNS` \[20\] per fraction with seeds `FIRST_SEED` \[1000\] onwards (the
//! stereo sweep's): `OUT_DIR/plain/stereo_n0.000_o{f}_r{run}.csv` holds plain
//! coordinates, `OUT_DIR/cov/` the same points with their covariance columns; each CSV has
//! its truth JSON beside it.

use std::path::PathBuf;
use std::process::ExitCode;

use swarmpose_sim::StereoSpec;
use swarmpose_sim::export::write_stereo_scenario;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first().map(PathBuf::from) else {
        eprintln!("usage: export_stereo OUT_DIR [RUNS] [FIRST_SEED]");
        return ExitCode::from(2);
    };
    let number = |i: usize, default: u64| -> Option<u64> {
        args.get(i).map_or(Some(default), |v| v.parse().ok())
    };
    let (Some(runs), Some(first)) = (number(1, 20), number(2, 1000)) else {
        eprintln!("RUNS and FIRST_SEED must be whole numbers");
        return ExitCode::from(2);
    };
    let mut written = 0;
    for fraction in [0.9, 0.95, 0.97] {
        let spec = StereoSpec::street().with_outliers(fraction);
        for run in 0..runs {
            let seed = first + run;
            let result = spec.scenario(seed).and_then(|s| {
                let name = format!("stereo_n0.000_o{fraction:.2}_r{run:03}");
                for (sub, cov) in [("plain", false), ("cov", true)] {
                    let dir = out.join(sub);
                    std::fs::create_dir_all(&dir).map_err(|e| swarmpose_sim::SimError::Io {
                        path: dir.clone(),
                        source: e,
                    })?;
                    write_stereo_scenario(&dir, &name, &s, fraction, seed, cov)?;
                }
                Ok(())
            });
            if let Err(e) = result {
                eprintln!("scenario seed {seed}: {e}");
                return ExitCode::FAILURE;
            }
            written += 1;
        }
    }
    println!(
        "wrote {written} scenarios to {}/plain and {}/cov",
        out.display(),
        out.display()
    );
    ExitCode::SUCCESS
}
