//! The `shadowlab` command line. Library errors become `anyhow` errors only here.

mod commands;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// The classic hardware shadow pipeline on Quake 3 maps, measured against an exact reference.
#[derive(Parser)]
#[command(name = "shadowlab", version, about, long_about = None)]
struct Cli {
    #[command(flatten)]
    common: commands::CommonArgs,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the GL context path taken, the capability probe and the fallbacks chosen.
    Info(commands::info::Args),
    /// Render one frame headless to a PNG.
    Render(commands::render::Args),
    /// List every option: key, type, default and meaning.
    Options(commands::options::Args),
    /// Print what a Quake 3 map holds, as JSON.
    Inspect(commands::inspect::Args),
    /// Measure frame time and error against the exact reference over a sweep of options.
    Bench(commands::bench::Args),
    /// Search the option space of one scene for the Pareto frontier of error against time.
    Tune(commands::tune::Args),
    /// Check maps of a data set: both techniques, planner on and off, against the reference.
    Check(commands::check::Args),
    /// Join the parts of a sharded run (`check --shard K/N --out DIR`) into what one run
    /// writes.
    Merge(commands::merge::Args),
    /// Record a flythrough: a camera walking through a scene's map, as a path file.
    Flythrough(commands::flythrough::Args),
    /// Subdivide each light's receivers into lit and shadowed fragments (Vector's light-volume
    /// subdivision), kept on disk; `--check` compares it with the ray-cast reference.
    Subdivide(commands::subdivide::Args),
    /// Regenerate the paper's figures and claims beside our measurements (index.html + .md).
    Reproduce(commands::reproduce::Args),
    /// Open the walkthrough viewer in a window (F1 for keys).
    #[cfg(feature = "window")]
    View(commands::view::Args),
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    commands::allocator::return_large_blocks();
    let cli = Cli::parse();
    let result: Result<()> = match cli.command {
        Command::Info(a) => commands::info::run(&cli.common, &a),
        Command::Render(a) => commands::render::run(&cli.common, &a),
        Command::Flythrough(a) => commands::flythrough::run(&cli.common, &a),
        Command::Subdivide(a) => commands::subdivide::run(&cli.common, &a),
        Command::Options(a) => commands::options::run(&a),
        Command::Inspect(a) => commands::inspect::run(&cli.common, &a),
        Command::Bench(a) => commands::bench::run(&cli.common, &a),
        Command::Tune(a) => commands::tune::run(&cli.common, &a),
        Command::Check(a) => commands::check::run(&cli.common, &a),
        Command::Merge(a) => commands::merge::run(&a),
        Command::Reproduce(a) => commands::reproduce::run(&cli.common, &a),
        #[cfg(feature = "window")]
        Command::View(a) => commands::view::run(&cli.common, &a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", commands::error_message(&e));
        std::process::exit(1);
    }
}
