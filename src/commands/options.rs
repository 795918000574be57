//! `shadowlab options`: every key, its type, default and meaning.

use anyhow::Result;
use shadowlab::options::Options;

#[derive(clap::Args)]
pub struct Args {
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<()> {
    let specs = Options::specs();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&specs)?);
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
    Ok(())
}
