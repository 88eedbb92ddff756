//! The `implicit-psdr` command-line tool; its commands are the library's [`implicit_psdr::cli`].

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(implicit_psdr::cli::main(std::env::args_os()))
}
