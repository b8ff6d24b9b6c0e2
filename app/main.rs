//! Caustica's command line: `caustica render` renders a scene headless to EXR or PNG.
//! (The viewer will open when no subcommand is given; until then that prints the help.)
//!
//! Exit codes: 0 success, 1 runtime error (unreadable or invalid scene, unwritable output),
//! 2 bad arguments. Each error is one line naming the file or argument.

mod render;

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "caustica",
    version,
    about = "Interactive viewer for progressive, physically based light transport"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a glTF scene without a window and write the image (EXR or PNG).
    Render(render::RenderArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Some(Command::Render(args)) => match render::run(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(render::Failure::Usage(msg)) => {
                let cmd = Cli::command();
                let mut render = cmd
                    .find_subcommand("render")
                    .cloned()
                    .unwrap_or(cmd)
                    .bin_name("caustica render");
                render
                    .error(clap::error::ErrorKind::ValueValidation, msg)
                    .exit()
            }
            Err(render::Failure::Runtime(e)) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        None => {
            let _ = Cli::command().print_help();
            println!();
            ExitCode::SUCCESS
        }
    }
}
