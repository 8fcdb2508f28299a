//! The `enact-hub` binary: everything lives in the library; see `enact_hub::cli`.

fn main() -> std::process::ExitCode {
    enact_hub::cli::main()
}
