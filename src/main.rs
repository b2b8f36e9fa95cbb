//! The `penumbra` command line: turns library errors into one line and an exit code.
//!
//! Exit codes: 0 success, 1 an error (one `error: ...` line on stderr; with
//! `--verbose`, the error's source chain and debug form follow), 2 a usage
//! error (clap's message), 101 an internal error (a panic: a bug, reported as
//! one `error: internal error ...` line).

mod cli;

use std::process::ExitCode;
use std::sync::Mutex;

use clap::Parser;

/// The last panic's message and location, recorded by the panic hook so that
/// `main` can print it as one line (panics caught inside the library, if any,
/// leave it here unprinted).
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

fn main() -> ExitCode {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists.
    unsafe { penumbra::gpu::set_driver_defaults() };
    let args = cli::Cli::parse();
    let verbose = args.verbose;
    std::panic::set_hook(Box::new(move |info| {
        let mut text = match info.location() {
            Some(at) => format!("{} (at {at})", cli::panic_message(info.payload())),
            None => cli::panic_message(info.payload()),
        };
        if verbose {
            text.push_str(&format!("\n{}", std::backtrace::Backtrace::force_capture()));
        }
        if let Ok(mut last) = LAST_PANIC.lock() {
            *last = Some(text);
        }
    }));
    match std::panic::catch_unwind(|| cli::run(args)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("{}", cli::error_report(&e, verbose));
            ExitCode::FAILURE
        }
        Err(_) => {
            let text = LAST_PANIC
                .lock()
                .ok()
                .and_then(|mut last| last.take())
                .unwrap_or_else(|| "unknown panic".to_owned());
            let mut lines = text.lines();
            eprintln!(
                "error: internal error (a bug in penumbra, please report it): {}",
                lines.next().unwrap_or_default()
            );
            for line in lines {
                eprintln!("{line}");
            }
            ExitCode::from(101)
        }
    }
}
