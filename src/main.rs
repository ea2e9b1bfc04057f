//! The `lightcuts` binary: see `lightcuts --help`.

fn main() {
    // Output piped into a reader that stops early (`| head`) ends the
    // process by SIGPIPE, as for any Unix tool, not a panic.
    sigpipe::reset();
    std::process::exit(lightcuts::cli::main());
}
