//! `radiosity`: the command-line front end (the library `radiosity_cli` holds its commands).

fn main() -> std::process::ExitCode {
    radiosity_cli::main()
}
