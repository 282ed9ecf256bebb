//! The `gpurt` command line: parses the arguments, runs the command (`cli`), and turns
//! its outcome into an exit code: 0 success, 1 `diff` over its thresholds (or `--backend
//! both` with images that differ), 2 bad input or failure, 130 interrupted.

mod cli;

use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use gpurt::Error;
use gpurt::scene::ReadOptions;

use cli::args::{Cli, Command};
use cli::{farm, render, sequence, shell, tools};

fn main() -> ExitCode {
    let launch = Instant::now();
    // Before any thread: the environment is written (`quiet_device_select`'s safety).
    gpurt::gpu::quiet_device_select();
    let args = Cli::parse();
    if let Some(n) = args.threads
        && let Err(e) = cli::use_threads(n)
    {
        eprintln!("gpurt: --threads {n}: {e}");
        return ExitCode::from(2);
    }
    // `gpurt inof s.nff` is a mistyped command, not two scenes.
    if args.command.is_none()
        && let Some(given) = args.render.scenes.first()
        && let Some(meant) = shell::meant_command(given)
    {
        eprintln!(
            "gpurt: '{}' is neither a scene file nor a command; did you mean `gpurt {meant}`?",
            given.display()
        );
        return ExitCode::from(2);
    }
    let result = match args.command {
        Some(Command::Completions { shell }) => shell::completions(shell),
        Some(Command::Man) => shell::man(),
        Some(Command::Info {
            scene,
            json,
            lenient,
        }) => tools::info(
            &scene,
            json,
            &ReadOptions {
                lenient,
                ..ReadOptions::default()
            },
        ),
        Some(Command::Diff(diff)) => tools::diff(diff),
        Some(Command::Bench(bench)) => tools::bench(bench),
        Some(Command::Tune(tune)) => tools::tune(tune),
        Some(Command::View(view)) => tools::view(view, launch),
        Some(Command::Merge { dir, output }) => farm::merge(&dir, &output),
        None => match (&args.render.out_dir, args.render.shard) {
            _ if args.render.frames.is_some() => sequence::sequence(&args.render),
            (Some(dir), _) => farm::batch(&args.render, dir),
            (None, Some(shard)) => farm::shard(&args.render, shard),
            (None, None) => render::render(args.render),
        },
    };
    match result {
        Ok(code) => code,
        Err(Error::Interrupted) => {
            eprintln!("gpurt: interrupted; no image written");
            ExitCode::from(130)
        }
        Err(e) => {
            cli::report::print_error(&e, "");
            ExitCode::from(2)
        }
    }
}
