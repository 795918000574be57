//! Viewer scripts (`shadowlab view --script FILE`): what a user does with keys and the panel,
//! as lines of text, so that tests, demos and README screenshots drive the real viewer.
//!
//! ```text
//! # one command per line; blank lines and # comments are skipped
//! wait 5                      # render 5 frames
//! set technique=shadow_volume # any option, as --set writes it
//! light 0 shadow_map          # light 0's technique (`default` removes the override)
//! select 1                    # the selected light (depth view, stencil view, editing)
//! view scene                  # scene | depth | stencil | error
//! face 2                      # which of an omni light's six depth images the depth view shows
//! overlay volumes on          # volumes | silhouettes | texels | timings | help
//! walkthrough 3               # stop the frame after step 3 (0-based); `walkthrough off`
//! camera 0 0 100 45 -10       # x y z yaw pitch
//! replay path.txt             # play a camera path, one pose per frame
//! record path.txt             # record the camera's poses until `record stop`
//! error                       # compute the error image against the exact reference, wait
//! sampled 4                   # render until the live error has sampled 4 more frames
//! screenshot out.png          # the window, panel and overlays included
//! frame out.png               # the 3D view only (the renderer's frame)
//! play off                    # the scene's motion (players, moving lights): on | off
//! time 2.5                    # go to this many seconds of the motion
//! step 3                      # step the motion by path frames (1/20 s; negative: back)
//! grab on                     # the selected light moves with the camera: on | off
//! quit
//! ```

use std::path::PathBuf;

/// What a view shows in place of the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewMode {
    Scene,
    /// The selected light's shadow map.
    Depth,
    /// The selected light's stencil counts after its volume pass.
    Stencil,
    /// Each pixel against the exact reference.
    Error,
}

impl ViewMode {
    pub const ALL: [ViewMode; 4] = [
        ViewMode::Scene,
        ViewMode::Depth,
        ViewMode::Stencil,
        ViewMode::Error,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Scene => "scene",
            ViewMode::Depth => "depth",
            ViewMode::Stencil => "stencil",
            ViewMode::Error => "error",
        }
    }
}

/// A toggle of the viewer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Toggle {
    Volumes,
    Silhouettes,
    Texels,
    Timings,
    Help,
    /// The live sampled error.
    Estimate,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    Wait(usize),
    /// Render until the live error (`overlay estimate on`) has sampled this many more frames:
    /// how many frames that takes follows `estimate.budget` and the machine's speed, what the
    /// script then reads does not.
    Sampled(usize),
    Set(String),
    LightTechnique(usize, Option<crate::options::Technique>),
    Select(usize),
    View(ViewMode),
    Face(usize),
    Overlay(Toggle, bool),
    Walkthrough(Option<usize>),
    Camera([f32; 5]),
    Replay(PathBuf),
    Record(Option<PathBuf>),
    Error,
    Screenshot(PathBuf),
    Frame(PathBuf),
    /// Play or pause the scene's motion.
    Play(bool),
    /// Go to this time of the motion (seconds).
    Time(f64),
    /// Step the motion by path frames.
    Step(i64),
    /// Grab or drop the selected light.
    Grab(bool),
    Quit,
}

#[derive(Debug, thiserror::Error, PartialEq)]
#[error("script line {line}: {message}")]
pub struct ScriptError {
    pub line: usize,
    pub message: String,
}

fn on_off(word: &str) -> Result<bool, String> {
    match word {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        other => Err(format!("`{other}` is not on or off")),
    }
}

fn parse_line(line: &str) -> Result<Option<Command>, String> {
    let line = line.split('#').next().unwrap_or("").trim();
    if line.is_empty() {
        return Ok(None);
    }
    let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
    let rest = rest.trim();
    let args: Vec<&str> = rest.split_whitespace().collect();
    let number = |s: Option<&&str>| -> Result<usize, String> {
        s.ok_or("a number is missing")?
            .parse::<usize>()
            .map_err(|e| e.to_string())
    };
    let path = || -> Result<PathBuf, String> {
        (!rest.is_empty())
            .then(|| PathBuf::from(rest))
            .ok_or_else(|| format!("`{word}` needs a file"))
    };
    let command = match word {
        "wait" => Command::Wait(if args.is_empty() {
            1
        } else {
            number(args.first())?
        }),
        "sampled" => Command::Sampled(number(args.first())?),
        "set" => {
            if !rest.contains('=') {
                return Err(format!("`set {rest}` is not key=value"));
            }
            Command::Set(rest.to_string())
        }
        "light" => {
            let index = number(args.first())?;
            let technique = match args.get(1).copied() {
                Some("default") => None,
                Some(t) => Some(
                    <crate::options::Technique as crate::options::OptionValue>::parse_value(t)?,
                ),
                None => return Err("`light N TECHNIQUE` needs a technique".into()),
            };
            Command::LightTechnique(index, technique)
        }
        "select" => Command::Select(number(args.first())?),
        "view" => Command::View(
            ViewMode::ALL
                .into_iter()
                .find(|m| Some(&m.name()) == args.first())
                .ok_or("expected view scene|depth|stencil|error")?,
        ),
        "face" => Command::Face(number(args.first())?),
        "overlay" => {
            let toggle = match args.first().copied() {
                Some("volumes") => Toggle::Volumes,
                Some("silhouettes") => Toggle::Silhouettes,
                Some("texels") => Toggle::Texels,
                Some("timings") => Toggle::Timings,
                Some("help") => Toggle::Help,
                Some("estimate") => Toggle::Estimate,
                _ => {
                    return Err(
                        "expected overlay volumes|silhouettes|texels|timings|help|estimate".into(),
                    );
                }
            };
            Command::Overlay(toggle, on_off(args.get(1).copied().unwrap_or("on"))?)
        }
        "walkthrough" => match args.first().copied() {
            Some("off") => Command::Walkthrough(None),
            _ => Command::Walkthrough(Some(number(args.first())?)),
        },
        "camera" => {
            let v: Vec<f32> = args
                .iter()
                .map(|a| a.parse::<f32>().map_err(|e| e.to_string()))
                .collect::<Result<_, _>>()?;
            if v.len() != 5 || !v.iter().all(|x| x.is_finite()) {
                return Err("`camera` needs x y z yaw pitch".into());
            }
            Command::Camera([v[0], v[1], v[2], v[3], v[4]])
        }
        "replay" => Command::Replay(path()?),
        "record" => match rest {
            "stop" => Command::Record(None),
            _ => Command::Record(Some(path()?)),
        },
        "error" => Command::Error,
        "screenshot" => Command::Screenshot(path()?),
        "frame" => Command::Frame(path()?),
        "play" => Command::Play(on_off(args.first().copied().unwrap_or("on"))?),
        "time" => Command::Time(
            args.first()
                .and_then(|a| a.parse::<f64>().ok())
                .filter(|t| t.is_finite() && *t >= 0.0)
                .ok_or("`time` needs seconds >= 0")?,
        ),
        "step" => Command::Step(
            args.first()
                .map_or(Ok(1), |a| a.parse::<i64>())
                .map_err(|e| e.to_string())?,
        ),
        "grab" => Command::Grab(on_off(args.first().copied().unwrap_or("on"))?),
        "quit" | "exit" => Command::Quit,
        other => return Err(format!("unknown command `{other}`")),
    };
    Ok(Some(command))
}

/// Parses a whole script; errors name the line.
pub fn parse(text: &str) -> Result<Vec<Command>, ScriptError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        match parse_line(line) {
            Ok(Some(c)) => out.push(c),
            Ok(None) => {}
            Err(message) => {
                return Err(ScriptError {
                    line: i + 1,
                    message,
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::Technique;

    #[test]
    fn scripts_parse_with_comments_and_defaults() {
        let s = parse(
            "# demo\nwait 3\nset technique=shadow_map\n\nlight 1 shadow_volume\nlight 0 default\n\
             view stencil  # counts\noverlay volumes\noverlay help off\nwalkthrough 2\n\
             walkthrough off\ncamera 1 2 3 90 -5\nrecord stop\nscreenshot a b.png\nsampled 4\nquit\n",
        )
        .unwrap();
        assert_eq!(
            s,
            vec![
                Command::Wait(3),
                Command::Set("technique=shadow_map".into()),
                Command::LightTechnique(1, Some(Technique::ShadowVolume)),
                Command::LightTechnique(0, None),
                Command::View(ViewMode::Stencil),
                Command::Overlay(Toggle::Volumes, true),
                Command::Overlay(Toggle::Help, false),
                Command::Walkthrough(Some(2)),
                Command::Walkthrough(None),
                Command::Camera([1.0, 2.0, 3.0, 90.0, -5.0]),
                Command::Record(None),
                Command::Screenshot("a b.png".into()),
                Command::Sampled(4),
                Command::Quit,
            ]
        );
    }

    #[test]
    fn mistakes_name_their_line() {
        for (text, line) in [
            ("wait x", 1),
            ("wait 1\nset nothing", 2),
            ("view sideways", 1),
            ("camera 1 2 3", 1),
            ("\n\nlight 0 magic", 3),
            ("frobnicate", 1),
            ("screenshot", 1),
            ("sampled", 1),
        ] {
            assert_eq!(parse(text).unwrap_err().line, line, "{text}");
        }
    }
}
