//! `tensegrity-fmu`: simulate scenes, print built-in scenes and run the scaling benchmark.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    quiet_broken_pipe();
    if let Err(message) = cli::interrupt::install() {
        eprintln!("error: {message}");
        return ExitCode::FAILURE;
    }
    let args = cli::Cli::parse();
    if let Err(message) = tensegrity_fmu::simd::forced_scalar() {
        eprintln!("error: {message}");
        return ExitCode::FAILURE;
    }
    match cli::run(args) {
        // Stopped by Ctrl-C with what it had written kept: as a shell reports an interrupt.
        Ok(()) if cli::interrupt::stop_requested() => ExitCode::from(130),
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// `tensegrity-fmu bench | head` and the like: when the reader goes away, end quietly as
/// other Unix tools do (killed by SIGPIPE) instead of panicking in `println!`.
fn quiet_broken_pipe() {
    #[cfg(unix)]
    // SAFETY: restores the default disposition of SIGPIPE before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
