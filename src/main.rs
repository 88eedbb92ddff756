//! The `implicit-psdr` command-line tool: parses arguments and calls the library.

fn main() {
    todo!("cli")
}
