//! The `graspd` binary: configuration, logs, runtime, signals.

use clap::Parser;
use graspd::config::{Cli, Settings};
use graspd::{server, telemetry};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let settings = match Settings::resolve(&cli) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("graspd: {e}");
            return ExitCode::from(2);
        }
    };
    if cli.probe {
        return match graspd::probe::probe(&settings) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("graspd: not ready: {e}");
                ExitCode::FAILURE
            }
        };
    }
    if cli.print_config {
        match toml::to_string(&settings) {
            Ok(text) => {
                print!("{text}");
                // The tokens themselves are never printed.
                println!(
                    "# auth_tokens: {} configured (not shown)",
                    settings.auth_tokens.len()
                );
                return ExitCode::SUCCESS;
            }
            Err(e) => {
                eprintln!("graspd: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    if let Err(e) = telemetry::init(&settings.log, settings.log_format) {
        eprintln!("graspd: {e}");
        return ExitCode::from(2);
    }
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("graspd: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    // The signal handlers are installed before anything listens (`shutdown_signal`).
    let shutdown = {
        let _runtime = runtime.enter();
        server::shutdown_signal()
    };
    match runtime.block_on(server::run(&settings, shutdown)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!(error = %e, "graspd failed");
            eprintln!("graspd: {e}");
            ExitCode::FAILURE
        }
    }
}
