//! Sharded runs: a long command's independent units (`check`'s maps, `bench`'s configurations,
//! `reproduce`'s scenes and sweeps) split deterministically
//! into N shards that separate processes or machines run (`--shard K/N --out DIR`), each writing
//! its part with a manifest; `shadowlab merge` joins the parts into what one run writes. Spreading
//! the shards is left to a job runner (docs/shards.md).

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The manifest's file name in a part's folder.
pub const MANIFEST: &str = "shard.json";

#[derive(Debug, Error, PartialEq)]
pub enum ShardError {
    #[error("--shard {0}: expected K/N with 1 <= K <= N (e.g. 1/2)")]
    Syntax(String),
    #[error("no parts given to merge")]
    Nothing,
    #[error("{0}: not a part of a sharded run ({MANIFEST} missing or unreadable: {1})")]
    NotAPart(PathBuf, String),
    #[error("{0} is a part of `{1}`, {2} of `{3}`: parts of different commands")]
    Commands(PathBuf, String, PathBuf, String),
    #[error(
        "{0} and {1} were run with different settings or code (units, options or version differ)"
    )]
    Settings(PathBuf, PathBuf),
    #[error("{0} and {1} are both shard {2}/{3}")]
    Twice(PathBuf, PathBuf, usize, usize),
    #[error("shard {0}/{1} missing: give every part from 1/{1} to {1}/{1}")]
    Missing(usize, usize),
    #[error("{0}: {1}")]
    Read(PathBuf, String),
    #[error("no part holds the result of {0} (a shard stopped before it?)")]
    UnitMissing(String),
    #[error("the result of {0} is given twice")]
    UnitTwice(String),
    #[error("a result for {0}, which the run does not list")]
    UnitUnknown(String),
}

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// The whole run as one shard.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// `K/N`.
    pub fn parse(text: &str) -> Result<Shard, ShardError> {
        let bad = || ShardError::Syntax(text.to_string());
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Whether unit `i` of the run's list is this shard's: every N-th from the K-th, so that
    /// shards of a list sorted by name get maps of every size alike.
    pub fn takes(&self, i: usize) -> bool {
        i % self.count == self.index - 1
    }
}

/// What a part of a sharded run holds, written beside its results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The command (`check`).
    pub command: String,
    pub shard: Shard,
    /// Every unit of the whole run, in its order (not only this shard's).
    pub units: Vec<String>,
    /// What the results depend on besides the units: options, the command's own arguments.
    pub settings: String,
    /// The code that made them (`CARGO_PKG_VERSION`).
    pub version: String,
}

impl Manifest {
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(dir.join(MANIFEST), text)
    }

    pub fn read(dir: &Path) -> Result<Manifest, ShardError> {
        let not = |e: String| ShardError::NotAPart(dir.to_path_buf(), e);
        let text = std::fs::read_to_string(dir.join(MANIFEST)).map_err(|e| not(e.to_string()))?;
        serde_json::from_str(&text).map_err(|e| not(e.to_string()))
    }
}

/// The parts of one run, checked to be all of it exactly once: returned in shard order, with
/// the manifest they share.
pub fn complete_run(dirs: &[PathBuf]) -> Result<(Manifest, Vec<PathBuf>), ShardError> {
    let parts: Vec<(PathBuf, Manifest)> = dirs
        .iter()
        .map(|d| Ok((d.clone(), Manifest::read(d)?)))
        .collect::<Result<_, ShardError>>()?;
    let (first_dir, first) = parts.first().ok_or(ShardError::Nothing)?;
    let count = first.shard.count;
    let mut by_index: Vec<Option<PathBuf>> = vec![None; count];
    for (dir, m) in &parts {
        if m.command != first.command {
            return Err(ShardError::Commands(
                first_dir.clone(),
                first.command.clone(),
                dir.clone(),
                m.command.clone(),
            ));
        }
        let same = m.units == first.units
            && m.settings == first.settings
            && m.version == first.version
            && m.shard.count == count;
        if !same {
            return Err(ShardError::Settings(first_dir.clone(), dir.clone()));
        }
        let slot = &mut by_index[m.shard.index - 1];
        if let Some(other) = slot {
            return Err(ShardError::Twice(
                other.clone(),
                dir.clone(),
                m.shard.index,
                count,
            ));
        }
        *slot = Some(dir.clone());
    }
    let ordered = by_index
        .into_iter()
        .enumerate()
        .map(|(i, d)| d.ok_or(ShardError::Missing(i + 1, count)))
        .collect::<Result<Vec<_>, _>>()?;
    let whole = Manifest {
        shard: Shard::WHOLE,
        ..first.clone()
    };
    Ok((whole, ordered))
}

/// The results of a run's parts (`results`, one per unit, `unit_of` naming each one's unit) in
/// the run's order: every unit exactly once.
pub fn in_run_order<T>(
    units: &[String],
    results: Vec<T>,
    unit_of: impl Fn(&T) -> String,
) -> Result<Vec<T>, ShardError> {
    let mut slots: Vec<Option<T>> = units.iter().map(|_| None).collect();
    for r in results {
        let unit = unit_of(&r);
        let i = units
            .iter()
            .position(|u| *u == unit)
            .ok_or_else(|| ShardError::UnitUnknown(unit.clone()))?;
        if slots[i].replace(r).is_some() {
            return Err(ShardError::UnitTwice(unit));
        }
    }
    slots
        .into_iter()
        .zip(units)
        .map(|(r, u)| r.ok_or_else(|| ShardError::UnitMissing(u.clone())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_every_unit_once() {
        assert_eq!(Shard::parse("2/3"), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/2", "3/2", "1", "a/b", "1/0", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        for count in 1..6 {
            for unit in 0..20 {
                let owners = (1..=count)
                    .filter(|&index| Shard { index, count }.takes(unit))
                    .count();
                assert_eq!(owners, 1, "unit {unit} of {count} shards");
            }
        }
    }

    #[test]
    fn a_run_is_complete_only_with_each_shard_once() {
        let root = std::env::temp_dir().join(format!("shadowlab-shard-{}", std::process::id()));
        let part = |name: &str, index: usize, settings: &str| {
            let dir = root.join(name);
            Manifest {
                command: "check".into(),
                shard: Shard { index, count: 2 },
                units: vec!["a".into(), "b".into(), "c".into()],
                settings: settings.into(),
                version: "1".into(),
            }
            .write(&dir)
            .unwrap();
            dir
        };
        let (one, two) = (part("one", 1, "s"), part("two", 2, "s"));
        let (whole, order) = complete_run(&[two.clone(), one.clone()]).unwrap();
        assert_eq!(order, vec![one.clone(), two.clone()]);
        assert_eq!(whole.shard, Shard::WHOLE);
        assert_eq!(
            complete_run(std::slice::from_ref(&one)),
            Err(ShardError::Missing(2, 2))
        );
        assert!(matches!(
            complete_run(&[one.clone(), one.clone()]),
            Err(ShardError::Twice(..))
        ));
        let other = part("other", 2, "t");
        assert!(matches!(
            complete_run(&[one.clone(), other]),
            Err(ShardError::Settings(..))
        ));
        assert!(matches!(
            complete_run(&[root.join("none")]),
            Err(ShardError::NotAPart(..))
        ));
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn results_come_back_in_the_runs_order_each_once() {
        let units: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let first = |s: &&str| s[..1].to_string();
        assert_eq!(
            in_run_order(&units, vec!["c3", "a1", "b2"], first),
            Ok(vec!["a1", "b2", "c3"])
        );
        assert_eq!(
            in_run_order(&units, vec!["c3", "a1"], first),
            Err(ShardError::UnitMissing("b".into()))
        );
        assert_eq!(
            in_run_order(&units, vec!["a1", "a2", "b", "c"], first),
            Err(ShardError::UnitTwice("a".into()))
        );
        assert_eq!(
            in_run_order(&units, vec!["d"], first),
            Err(ShardError::UnitUnknown("d".into()))
        );
    }
}
