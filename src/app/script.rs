//! Scripted viewer runs (`hybrid-rt view --script ...`), so tests and users can drive the
//! window reproducibly: a list of commands run in order, separated by commas, semicolons or
//! new lines (`#` starts a comment). `--script @FILE` reads them from a file.
//!
//! | command | what it does |
//! |---|---|
//! | `frames=N` | render and show N new frames |
//! | `view=NAME` | show a named pass output (`gbuffer.normal`, `tonemap.color`, ...) |
//! | `screenshot=PATH` | show the current frame again and save the window's pixels (without the overlay) as PNG |
//! | `capture=DIR` | dump every pass output of the current frame, as `render --dump-passes` does |
//! | `camera=NAME\|INDEX` | look through a scene camera; `camera=fly` or `camera=orbit`: the viewer's camera, from where the view is |
//! | `pause`, `play`, `step` | animation: stop, go on, advance one frame time while stopped |
//! | `reload` | recompile the watched shaders now (errors are shown and printed; the old ones stay) |
//! | `ui=on\|off`, `vsync=on\|off` | the overlay, the presentation mode |
//! | `KEY=VALUE` | a tunable (see [`super::tunables`]), applied before the next frame |
//! | `quit` | close the window and exit |
//!
//! A script that ends without `quit` leaves the window open for interactive use.

use super::tunables;
use anyhow::{Result, bail};
use std::path::PathBuf;

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Frames(u32),
    View(String),
    Screenshot(PathBuf),
    Capture(PathBuf),
    Camera(String),
    Pause,
    Play,
    Step,
    Reload,
    Ui(bool),
    Vsync(bool),
    Set(String, String),
    Quit,
}

/// `--script TEXT` or `--script @FILE`.
pub fn load(arg: &str) -> Result<Vec<Command>> {
    match arg.strip_prefix('@') {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("--script @{path}: {e}"))?;
            parse(&text).map_err(|e| anyhow::anyhow!("{path}: {e}"))
        }
        None => parse(arg),
    }
}

pub fn parse(text: &str) -> Result<Vec<Command>> {
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        for item in line.split([',', ';']).map(str::trim).filter(|s| !s.is_empty()) {
            out.push(parse_one(item)?);
        }
    }
    Ok(out)
}

fn on_off(key: &str, v: &str) -> Result<bool> {
    tunables::parse_bool(v).ok_or_else(|| anyhow::anyhow!("script: {key}={v}: expected on or off"))
}

fn parse_one(item: &str) -> Result<Command> {
    let (key, value) = match item.split_once('=') {
        Some((k, v)) => (k.trim(), Some(v.trim())),
        None => (item, None),
    };
    let need = |v: Option<&str>| match v {
        Some(v) if !v.is_empty() => Ok(v.to_string()),
        _ => bail!("script: {key} needs a value ({key}=...)"),
    };
    Ok(match (key, value) {
        ("frames", v) => {
            let v = need(v)?;
            Command::Frames(v.parse().map_err(|_| anyhow::anyhow!("script: frames={v}: expected a whole number"))?)
        }
        ("view", v) => Command::View(need(v)?),
        ("screenshot", v) => Command::Screenshot(need(v)?.into()),
        ("capture", v) => Command::Capture(need(v)?.into()),
        ("camera", v) => Command::Camera(need(v)?),
        ("ui", v) => Command::Ui(on_off(key, &need(v)?)?),
        ("vsync", v) => Command::Vsync(on_off(key, &need(v)?)?),
        ("pause", None) => Command::Pause,
        ("play", None) => Command::Play,
        ("step", None) => Command::Step,
        ("reload", None) => Command::Reload,
        ("quit", None) => Command::Quit,
        (k, Some(v)) if tunables::find(k).is_some() => Command::Set(k.to_string(), v.to_string()),
        _ => bail!(
            "script: unknown command '{item}' (commands: frames=N, view=NAME, screenshot=PATH, capture=DIR, camera=NAME, \
             pause, play, step, reload, ui=on|off, vsync=on|off, quit, or KEY=VALUE with KEY one of {})",
            tunables::ALL.iter().map(|t| t.name).collect::<Vec<_>>().join(", ")
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_commands_in_order() {
        let s = parse("frames=8, view=gbuffer.normal; screenshot=a b.png\n# comment\ntaa=off,quit").unwrap();
        assert_eq!(
            s,
            vec![
                Command::Frames(8),
                Command::View("gbuffer.normal".into()),
                Command::Screenshot("a b.png".into()),
                Command::Set("taa".into(), "off".into()),
                Command::Quit,
            ]
        );
    }

    #[test]
    fn rejects_unknown_and_malformed_commands() {
        for bad in ["frames=x", "frames", "jump", "view=", "ui=maybe", "nonsense=1"] {
            assert!(parse(bad).is_err(), "{bad} must be refused");
        }
    }
}
