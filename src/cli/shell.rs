//! What the command line offers around its commands: completion scripts for each shell
//! and the manual page, both generated from the parser's own definitions (so they never
//! disagree with it), and a suggestion when a mistyped command is taken for a scene.

use std::path::Path;
use std::process::ExitCode;

use clap::CommandFactory;
use gpurt::out;

use super::args::Cli;

/// `gpurt completions SHELL`: the script on stdout.
pub fn completions(shell: clap_complete::Shell) -> gpurt::Result<ExitCode> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "gpurt", &mut script);
    out!("{}", String::from_utf8_lossy(&script));
    Ok(ExitCode::SUCCESS)
}

/// `gpurt man`: the roff page on stdout: the render command's options, then a section a
/// subcommand with its synopsis, description and options (clap_mangen renders one
/// command a page; the subcommands' sections are demoted to subsections of theirs).
pub fn man() -> gpurt::Result<ExitCode> {
    let cmd = Cli::command();
    let failed = |e: std::io::Error| gpurt::Error::Render(format!("man: {e}"));
    let mut page = Vec::new();
    clap_mangen::Man::new(cmd.clone())
        .render(&mut page)
        .map_err(failed)?;
    // clap_mangen names each subcommand as a page of its own (`gpurt-info(1)`), which is
    // never installed: its text is a section further down this page.
    let mut page = refer_to_sections(&page);
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        let name = sub.get_name();
        let man = clap_mangen::Man::new(sub.clone().bin_name(format!("gpurt {name}")));
        let mut section = Vec::new();
        man.render_synopsis_section(&mut section)
            .and_then(|()| man.render_description_section(&mut section))
            .and_then(|()| man.render_options_section(&mut section))
            .map_err(failed)?;
        if sub.get_after_help().is_some() {
            man.render_extra_section(&mut section).map_err(failed)?;
        }
        page.extend_from_slice(format!(".SH \"GPURT {}\"\n", name.to_uppercase()).as_bytes());
        page.extend_from_slice(&demote_headings(&section));
    }
    out!("{}", String::from_utf8_lossy(&page));
    Ok(ExitCode::SUCCESS)
}

/// The root page's list of subcommands, each `gpurt\-NAME(1)` made `gpurt NAME` and the
/// section of this page that has it.
fn refer_to_sections(roff: &[u8]) -> Vec<u8> {
    String::from_utf8_lossy(roff)
        .lines()
        .map(|l| {
            match l
                .strip_prefix("gpurt\\-")
                .and_then(|rest| rest.strip_suffix("(1)"))
            {
                Some("help") => "\\fBgpurt help\\fR\n".to_string(),
                Some(name) => format!(
                    "\\fBgpurt {name}\\fR (section GPURT {} below)\n",
                    name.to_uppercase()
                ),
                None => format!("{l}\n"),
            }
        })
        .collect::<String>()
        .into_bytes()
}

/// A subcommand's sections as subsections of its own section: `.SH` becomes `.SS`.
fn demote_headings(roff: &[u8]) -> Vec<u8> {
    String::from_utf8_lossy(roff)
        .lines()
        .map(|l| match l.strip_prefix(".SH ") {
            Some(title) => format!(".SS {title}\n"),
            None => format!("{l}\n"),
        })
        .collect::<String>()
        .into_bytes()
}

/// The command `word` was probably meant to be, when a render was asked for with `word`
/// as its first scene: `word` names no file, has no extension or directory, and is close
/// to a command's name (Jaro similarity as clap's own suggestions use, 0.7 or more).
pub fn meant_command(word: &Path) -> Option<String> {
    if word.exists() || word.extension().is_some() || word.components().count() != 1 {
        return None;
    }
    let word = word.to_str()?;
    Cli::command()
        .get_subcommands()
        .filter(|s| !s.is_hide_set())
        .map(|s| s.get_name().to_string())
        .chain(["help".to_string()])
        .map(|name| (strsim::jaro(word, &name), name))
        .filter(|(score, _)| *score >= 0.7)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name)| name)
}
