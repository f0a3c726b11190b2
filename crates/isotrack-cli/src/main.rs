//! The `isotrack` binary: parse arguments, dispatch, map failures to exit codes.
use clap::Parser;
use isotrack_cli::cli::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    // clap's own errors exit 2 by default; every usage error of isotrack exits 64 (one table,
    // README "Exit codes"), so they are mapped here. Help and version exit 0.
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                isotrack_cli::exit::USAGE
            } else {
                isotrack_cli::exit::OK
            });
        }
    };
    let result = match &cli.command {
        Command::Run(args) => isotrack_cli::run::run(args),
        Command::Show(args) => isotrack_cli::run::show(args),
        Command::Check(args) => isotrack_cli::run::check(args),
        Command::Compare(args) => isotrack_cli::compare::compare(args),
        Command::Plot(args) => isotrack_cli::figures::plot(args),
        Command::Figures(args) => isotrack_cli::figures::figures(args),
        Command::Sweep(args) => isotrack_cli::sweep::sweep(args),
        Command::Merge(args) => isotrack_cli::sweep::merge(args),
        Command::Trim(args) => isotrack_cli::aircraft::trim(args),
        Command::Replay(args) => isotrack_cli::aircraft::replay(args),
        Command::Interpolate(args) => isotrack_cli::interpolate::interpolate(args),
        Command::Benchmark(args) => isotrack_cli::bench::benchmark(args),
        Command::Report(args) => isotrack_cli::bench::report(args),
    };
    // A reader that closed standard output is not an error (exit 0); another failure to write
    // it is exit 73 unless the command failed first (see `isotrack_cli::console`).
    match result {
        Ok(()) => match isotrack_cli::console::stdout_failure() {
            None => ExitCode::from(isotrack_cli::exit::OK),
            Some(why) => {
                isotrack_cli::errln!("error: cannot write standard output: {why}");
                ExitCode::from(isotrack_cli::exit::CANTCREAT)
            }
        },
        Err(f) => {
            isotrack_cli::errln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}
