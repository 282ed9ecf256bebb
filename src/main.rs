//! The `gpurt` command line: argument parsing, calling the library, printing errors.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "gpurt",
    version,
    about = "Whitted ray tracer for NFF/SPD scenes and STL/OBJ meshes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print what a scene holds: camera, bounds, primitive counts, lights, materials, warnings.
    Info {
        scene: PathBuf,
        /// One JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("gpurt: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> gpurt::Result<ExitCode> {
    match cli.command {
        Command::Info { scene, json } => {
            let s = gpurt::scene::load(&scene)?;
            if json {
                println!("{}", gpurt::info::to_json(&s));
            } else {
                print!("{}", gpurt::info::to_text(&s));
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}
