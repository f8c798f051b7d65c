//! An external command as a bench method (docs/BENCHMARKS.md, "External methods"): a program
//! run on acr's render (a denoiser), its output scored like any method's image, its seconds
//! added to the render's.

use super::{CommandTime, Method};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// What a command's run measured.
#[derive(Clone, Copy, Debug)]
pub(super) struct CommandRun {
    /// Its seconds, counted as the method says.
    pub(super) seconds: f64,
}

/// Where `program` is: a name with a `/` is relative to the manifest's folder `base`, a bare
/// name is looked up on `PATH`; `None` when there is no such file.
pub(super) fn find_program(program: &str, base: &Path) -> Option<PathBuf> {
    if program.contains('/') {
        let p = base.join(program);
        return p.is_file().then_some(p);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// Why `method`'s rows are skipped on this machine, if they are: its program is absent. The
/// bench goes on without it, so that a manifest with a denoiser still runs where it is not
/// installed.
pub(super) fn skip_reason(method: &Method, base: &Path) -> Option<String> {
    let program = method.command.as_ref()?.first()?;
    find_program(program, base)
        .is_none()
        .then(|| format!("skipped: program \"{program}\" not found"))
}

/// Runs `method`'s command in the manifest's folder `base` with `{in}` and `{out}` replaced
/// by `input` and `output` (made absolute, since the command runs elsewhere); a program that
/// cannot start, a non-zero exit, no output image or, with `time = "printed"`, a last line that
/// is no number of seconds is an error naming the method.
pub(super) fn run_command(
    method: &Method,
    base: &Path,
    input: &Path,
    output: &Path,
) -> Result<CommandRun, String> {
    let label = &method.label;
    let argv = method
        .command
        .as_deref()
        .ok_or_else(|| format!("method \"{label}\" has no command"))?;
    let (program, args) = argv
        .split_first()
        .ok_or_else(|| format!("method \"{label}\": empty command"))?;
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_owned());
    // Absolute, since a relative program path would be taken from the child's folder.
    let program_path = find_program(program, base)
        .map(|p| absolute(&p))
        .ok_or_else(|| format!("method \"{label}\": program \"{program}\" not found"))?;
    let (input, output) = (absolute(input), absolute(output));
    let _ = std::fs::remove_file(&output);
    let mut cmd = Command::new(&program_path);
    cmd.current_dir(base);
    for a in args {
        cmd.arg(
            a.replace("{in}", &input.to_string_lossy())
                .replace("{out}", &output.to_string_lossy()),
        );
    }
    let start = Instant::now();
    let out = cmd
        .output()
        .map_err(|e| format!("method \"{label}\": cannot run \"{program}\": {e}"))?;
    let wall = start.elapsed().as_secs_f64();
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        let status = out.status.code().map_or_else(
            || "was killed by a signal".to_owned(),
            |c| format!("exit {c}"),
        );
        return Err(format!(
            "method \"{label}\": \"{program}\" {status}: {}",
            last.trim()
        ));
    }
    if !output.is_file() {
        return Err(format!(
            "method \"{label}\": \"{program}\" wrote no {}",
            output.display()
        ));
    }
    let seconds = match method.time.unwrap_or_default() {
        CommandTime::Wall => wall,
        CommandTime::Printed => printed_seconds(&String::from_utf8_lossy(&out.stdout))
            .map_err(|e| format!("method \"{label}\": time = \"printed\", but {e}"))?,
    };
    Ok(CommandRun { seconds })
}

/// The seconds on the last non-empty line of `stdout`: a finite number, not negative.
fn printed_seconds(stdout: &str) -> Result<f64, String> {
    let last = stdout
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .ok_or("it printed nothing")?;
    match last.parse::<f64>() {
        Ok(s) if s.is_finite() && s >= 0.0 => Ok(s),
        _ => Err(format!(
            "its last line \"{last}\" is not a number of seconds"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn printed_seconds_are_the_last_line_s_number() {
        assert_eq!(printed_seconds("loading\n0.250\n\n"), Ok(0.25));
        assert!(printed_seconds("").is_err_and(|e| e.contains("printed nothing")));
        assert!(printed_seconds("0.2\ndone\n").is_err_and(|e| e.contains("\"done\"")));
        assert!(printed_seconds("-1\n").is_err());
        assert!(printed_seconds("NaN\n").is_err());
    }

    #[cfg(unix)]
    #[test]
    fn commands_run_in_the_manifest_s_folder_and_their_failures_name_the_method() {
        let dir = std::env::temp_dir().join(format!("acr-bench-external-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let input = dir.join("in.exr");
        std::fs::write(&input, b"image").unwrap();
        let output = dir.join("out.pfm");
        let method = |argv: &[&str], time| Method {
            label: "den".to_owned(),
            command: Some(argv.iter().map(|s| (*s).to_owned()).collect()),
            time,
            ..Method::default()
        };
        // A program on PATH; its working folder is the manifest's; `{in}`/`{out}` replaced.
        let copy = method(
            &[
                "sh",
                "-c",
                "cp \"$0\" \"$1\" && pwd > where && echo 0.125",
                "{in}",
                "{out}",
            ],
            Some(CommandTime::Printed),
        );
        let run = run_command(&copy, &dir.join("sub"), &input, &output).unwrap();
        assert_eq!(run.seconds, 0.125);
        assert_eq!(std::fs::read(&output).unwrap(), b"image");
        let wd = std::fs::read_to_string(dir.join("sub/where")).unwrap();
        assert_eq!(
            Path::new(wd.trim()),
            std::fs::canonicalize(dir.join("sub")).unwrap()
        );
        // Wall time: the whole process's.
        let slow = method(
            &["sh", "-c", "sleep 0.2; cp \"$0\" \"$1\"", "{in}", "{out}"],
            None,
        );
        let run = run_command(&slow, &dir, &input, &output).unwrap();
        assert!(run.seconds >= 0.2 && run.seconds < 5.0, "{}", run.seconds);
        // Failures, each naming the method.
        let fail = method(
            &["sh", "-c", "echo no denoiser >&2; exit 3", "{in}", "{out}"],
            None,
        );
        let e = run_command(&fail, &dir, &input, &output).unwrap_err();
        assert!(
            e.contains("method \"den\"") && e.contains("exit 3: no denoiser"),
            "{e}"
        );
        let nothing = method(&["sh", "-c", "true", "{in}", "{out}"], None);
        let e = run_command(&nothing, &dir, &input, &output).unwrap_err();
        assert!(e.contains("wrote no"), "{e}");
        let words = method(
            &["sh", "-c", "cp \"$0\" \"$1\"; echo done", "{in}", "{out}"],
            Some(CommandTime::Printed),
        );
        let e = run_command(&words, &dir, &input, &output).unwrap_err();
        assert!(e.contains("\"done\" is not a number of seconds"), "{e}");
        // An absent program: skipped, by name or by a path relative to the manifest.
        for program in ["acr-no-such-program", "./tools/nothing.py"] {
            let absent = method(&[program, "{in}", "{out}"], None);
            let why = skip_reason(&absent, &dir).unwrap();
            assert!(why.contains(program), "{why}");
            let e = run_command(&absent, &dir, &input, &output).unwrap_err();
            assert!(e.contains("not found") && e.contains("\"den\""), "{e}");
        }
        // A program relative to a manifest's folder that is itself relative to ours.
        let script = dir.join("sub/tools/copy.sh");
        std::fs::create_dir_all(script.parent().unwrap()).unwrap();
        std::fs::write(&script, "#!/bin/sh\ncp \"$1\" \"$2\"\n").unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
        let cwd = std::env::current_dir().unwrap();
        let up: PathBuf = cwd.components().skip(1).map(|_| "..").collect();
        let relative = up.join(dir.join("sub").strip_prefix("/").unwrap());
        let tool = method(&["./tools/copy.sh", "{in}", "{out}"], None);
        assert_eq!(skip_reason(&tool, &relative), None);
        run_command(&tool, &relative, &input, &output).unwrap();
        assert_eq!(std::fs::read(&output).unwrap(), b"image");
        assert_eq!(skip_reason(&copy, &dir), None);
        assert_eq!(skip_reason(&Method::default(), &dir), None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
