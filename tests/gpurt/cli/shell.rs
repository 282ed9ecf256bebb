//! What the command line offers a shell: completion scripts that the shells accept, a
//! manual page that roff accepts with every subcommand in it, a suggestion for a mistyped
//! command, and the thread count.

use std::process::Command;

use crate::common::inputs::SCENE;
use crate::common::{gpurt, in_ci, skip, stderr, workdir};

/// Whether `tool` runs here; outside CI a missing tool skips the check that needs it.
fn have(tool: &str, why: &str) -> bool {
    if Command::new(tool).arg("--version").output().is_ok() {
        return true;
    }
    assert!(
        !in_ci(),
        "{tool} is missing (required under CI=true): {why}"
    );
    skip(&format!("{tool} is missing: {why}"));
    false
}

/// Every shell gets a script naming the commands; bash's parses in `bash -n`, zsh's and
/// fish's in theirs (skipped where those shells are not installed, but under CI=true). A
/// shell clap does not know is refused with the list.
#[test]
fn completion_scripts_name_every_command_and_parse_in_their_shells() {
    let d = workdir("completions");
    for (shell, check) in [
        ("bash", Some(("bash", "-n"))),
        ("zsh", Some(("zsh", "-n"))),
        ("fish", Some(("fish", "--no-execute"))),
        ("powershell", None),
        ("elvish", None),
    ] {
        let o = gpurt(&["completions", shell], &d);
        assert!(o.status.success(), "{shell}: {}", stderr(&o));
        let script = String::from_utf8_lossy(&o.stdout);
        for word in ["info", "bench", "merge", "shading", "threads"] {
            assert!(script.contains(word), "{shell}: no {word}");
        }
        let file = d.join(format!("gpurt.{shell}"));
        std::fs::write(&file, &o.stdout).unwrap();
        let Some((program, flag)) = check else {
            continue;
        };
        // Under CI=true each shell must be there (.ci/run installs zsh and fish).
        if !have(program, &format!("checks the {shell} completion script")) {
            continue;
        }
        let parsed = Command::new(program).arg(flag).arg(&file).output().unwrap();
        assert!(
            parsed.status.success(),
            "{shell}: {}",
            String::from_utf8_lossy(&parsed.stderr)
        );
    }
    // The check has teeth: a broken script fails it.
    std::fs::write(d.join("broken.bash"), "_gpurt() {\n  case x in\n}\n").unwrap();
    let broken = Command::new("bash")
        .args(["-n", "broken.bash"])
        .current_dir(&d)
        .output();
    assert!(
        !broken.unwrap().status.success(),
        "bash -n passed a broken script"
    );

    let o = gpurt(&["completions", "tcsh"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("possible values: bash"),
        "{}",
        stderr(&o)
    );
}

/// `gpurt man` is a roff page that groff formats without a warning, with a section for
/// each subcommand and their options.
#[test]
fn the_manual_page_is_accepted_by_groff_and_has_every_subcommand() {
    let d = workdir("man");
    let o = gpurt(&["man"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        page.starts_with(".ie") || page.contains(".TH gpurt 1"),
        "{page}"
    );
    for section in [
        "GPURT INFO",
        "GPURT DIFF",
        "GPURT MERGE",
        "GPURT VIEW",
        "GPURT BENCH",
        "GPURT COMPLETIONS",
        "GPURT MAN",
    ] {
        assert!(page.contains(&format!(".SH \"{section}\"")), "no {section}");
        // The list of subcommands refers to this section, not to a page of its own
        // (`gpurt-info(1)`), which is never installed.
        assert!(
            page.contains(&format!("(section {section} below)")),
            "no reference to {section}"
        );
    }
    assert!(
        !page.contains("(1)\n"),
        "a reference to another page: {page}"
    );
    for option in [
        "\\-\\-threads",
        "\\-\\-shading",
        "\\-\\-max\\-flip",
        "\\-\\-frames",
    ] {
        assert!(page.contains(option), "no {option}");
    }
    if !have(
        "groff",
        "formats the manual page (apt-get install groff-base)",
    ) {
        return;
    }
    std::fs::write(d.join("gpurt.1"), &o.stdout).unwrap();
    let format = |file: &str| {
        Command::new("groff")
            .args(["-man", "-Tutf8", "-ww", "-z", file])
            .current_dir(&d)
            .output()
            .expect("groff runs")
    };
    let out = format("gpurt.1");
    assert!(
        out.status.success() && out.stderr.is_empty(),
        "{}",
        stderr(&out)
    );
    // groff with -ww does complain about a page that is not well formed.
    std::fs::write(
        d.join("bad.1"),
        ".TH x 1\n.SH\n.unknownmacro\n\\fBunclosed\n",
    )
    .unwrap();
    assert!(
        !format("bad.1").stderr.is_empty(),
        "groff accepted a broken page"
    );
}

/// A near-miss of a command name where a scene is expected gets "did you mean", exit 2 and
/// no image; a scene file of that very name renders; a word like no command is a missing
/// scene.
#[test]
fn a_mistyped_command_is_named_and_a_file_of_that_name_still_renders() {
    let d = workdir("suggest");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    for (typo, meant) in [
        ("inof", "info"),
        ("bnech", "bench"),
        ("veiw", "view"),
        ("mrege", "merge"),
    ] {
        let o = gpurt(&[typo, "ball.nff", "--backend", "cpu"], &d);
        assert_eq!(o.status.code(), Some(2), "{typo}");
        let err = stderr(&o);
        assert!(
            err.starts_with(&format!(
                "gpurt: '{typo}' is neither a scene file nor a command"
            )) && err.contains(&format!("did you mean `gpurt {meant}`?")),
            "{err}"
        );
        assert!(!d.join("ball.png").exists() && !d.join(format!("{typo}.png")).exists());
    }
    std::fs::write(d.join("inof"), SCENE).unwrap();
    let o = gpurt(&["inof", "--backend", "cpu"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("inof.png").exists());
    let o = gpurt(&["zebra", "--backend", "cpu"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("gpurt: zebra: "), "{}", stderr(&o));
    assert!(!stderr(&o).contains("did you mean"), "{}", stderr(&o));
}

/// `--threads`/`-j` sets the threads that render (`-v` says how many), on renders,
/// batches and bench alike; the image does not depend on it; 0 is refused.
#[test]
fn the_thread_count_is_used_said_and_checked() {
    let d = workdir("threads");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let mut images = Vec::new();
    for (flag, n) in [("-j", "1"), ("--threads", "3")] {
        let out = format!("ball-{n}.png");
        let o = gpurt(
            &["ball.nff", flag, n, "-v", "--backend", "cpu", "-o", &out],
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("threads     {n} (")),
            "{}",
            stderr(&o)
        );
        assert!(
            stderr(&o).contains(&format!("CPU, {n} threads")),
            "{}",
            stderr(&o)
        );
        images.push(std::fs::read(d.join(&out)).unwrap());
    }
    assert_eq!(images[0], images[1], "the same image on 1 and 3 threads");
    let o = gpurt(
        &[
            "-j",
            "2",
            "ball.nff",
            "--out-dir",
            "batch",
            "-v",
            "--backend",
            "cpu",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("threads     2 ("), "{}", stderr(&o));
    let bench = [
        "bench",
        "ball.nff",
        "--sizes",
        "8x8",
        "--backend",
        "cpu",
        "-j",
        "1",
    ];
    let o = gpurt(&bench, &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("cpu         1 threads"),
        "{}",
        stderr(&o)
    );
    let o = gpurt(&["ball.nff", "-j", "0", "-o", "none.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("invalid value '0' for '--threads <N>'"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("none.png").exists());
}
