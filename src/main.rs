//! The `lightcuts` binary: see `lightcuts --help`.

fn main() {
    std::process::exit(lightcuts::cli::main());
}
