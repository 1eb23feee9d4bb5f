//! The `caustic` binary: the command line is a function of the library (`caustic::cli`), shared
//! with the Python module's `python -m caustic`.

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(caustic::cli::run(std::env::args_os()))
}
