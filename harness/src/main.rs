fn main() {
    // Before any allocation of the driver's: see run/allocator.rs for the faults this saves.
    harness::run::allocator::keep_freed_driver_memory();
    if let Err(e) = harness::cli::main_with_args(std::env::args_os()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
