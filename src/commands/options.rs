//! `shadowlab options`: every key, its type, default and meaning.

use anyhow::Result;
use shadowlab::options::Options;
use shadowlab::presets::Preset;

#[derive(clap::Args)]
pub struct Args {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<()> {
    let specs = Options::specs();
    if args.json {
        let presets: Vec<serde_json::Value> = Preset::ALL
            .into_iter()
            .map(|p| {
                serde_json::json!({
                    "name": p.name(),
                    "meaning": p.meaning(),
                    "values": p.values().iter().map(|(k, v)| (k.to_string(), v.to_string())).collect::<std::collections::BTreeMap<_, _>>(),
                })
            })
            .collect();
        let out = serde_json::json!({ "options": specs, "presets": presets });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    let kw = specs.iter().map(|s| s.key.len()).max().unwrap_or(3);
    let tw = specs
        .iter()
        .map(|s| s.type_name.len())
        .max()
        .unwrap_or(4)
        .min(36);
    let dw = specs.iter().map(|s| s.default.len()).max().unwrap_or(7);
    println!("{:kw$}  {:tw$}  {:dw$}  meaning", "key", "type", "default");
    for s in specs {
        println!(
            "{:kw$}  {:tw$}  {:dw$}  {}",
            s.key, s.type_name, s.default, s.meaning
        );
    }
    println!("\npresets (`--preset NAME`, applied before `--set`):");
    for p in Preset::ALL {
        println!("  {}: {}", p.name(), p.meaning());
        for (k, v) in p.values() {
            println!("      {k} = {v}");
        }
    }
    Ok(())
}
