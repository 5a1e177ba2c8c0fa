use std::process::ExitCode;

fn main() -> ExitCode {
    // Before any allocation of the driver's: see run/allocator.rs for the faults this saves.
    harness::run::allocator::keep_freed_driver_memory();
    match harness::cli::main_with_args(std::env::args_os()) {
        Ok(outcome) => outcome.exit_code(),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(harness::cli::EXIT_ERROR)
        }
    }
}
