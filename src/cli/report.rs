//! `convshadow report`: speed against error over kernels and slab counts, written as
//! `report.csv`, `report.md` and `speed_vs_error.png` (see `convshadow::report`).

use std::path::PathBuf;

use convshadow_common::model::scene::Penumbra;

use crate::cli::exit::{self, Failure};
use convshadow::report::{ReportOptions, run as run_report};

/// Arguments of `convshadow report`.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// Run the quick subset (under 2 minutes on 2 cores) instead of the full grid.
    #[arg(long)]
    pub quick: bool,
    /// Output folder (created if missing).
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// One line per case on stderr.
    #[arg(long, short)]
    pub verbose: bool,
    /// Run only case I (0-based: row I of the whole report's report.csv) and write report.csv
    /// with that row alone, for job arrays (docs/scale-out.md).
    #[arg(long, value_name = "I")]
    pub case: Option<usize>,
    /// Run one penumbra model only (`iterated` or `distance`); by default every case runs with
    /// both.
    #[arg(long, value_name = "iterated|distance", value_parser = super::parse_penumbra)]
    pub penumbra: Option<Penumbra>,
}

/// Runs `convshadow report`.
pub fn run(args: &ReportArgs) -> Result<i32, Failure> {
    if args.out.exists() && !args.out.is_dir() {
        return Err(Failure::new(
            exit::OUTPUT_FAILED,
            format!(
                "{}: --out names an existing file; expected a folder (created if missing)",
                args.out.display()
            ),
        ));
    }
    // A signal ends the run at once; a folder this run created is removed while still empty.
    exit::install_exit_on_signal((!args.out.exists()).then(|| args.out.clone()));
    let pool = super::thread_pool(args.threads)?;
    let options = ReportOptions {
        quick: args.quick,
        out: args.out.clone(),
        verbose: args.verbose,
        case: args.case,
        penumbra: args.penumbra,
    };
    let report = pool.install(|| run_report(&options)).map_err(|e| {
        let code = if e.starts_with("--case") {
            exit::BAD_ARGUMENTS
        } else {
            exit::OUTPUT_FAILED
        };
        Failure::new(code, e)
    })?;
    if let Some(c) = args.case {
        convshadow::outln!(
            "report: case {c} in {:.1} s → {}/report.csv",
            report.seconds,
            args.out.display()
        );
        return Ok(exit::OK);
    }
    convshadow::outln!(
        "report: {} cases in {:.0} s → {}/report.csv, report.md, speed_vs_error.png",
        report.rows.len(),
        report.seconds,
        args.out.display()
    );
    Ok(exit::OK)
}
