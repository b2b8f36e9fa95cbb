//! Command-line interface definitions and dispatch.

/// `eprint!` for progress lines: only when stderr is a terminal, so that logs and
/// tests see warnings and errors alone.
macro_rules! progress {
    ($($arg:tt)*) => {
        if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            eprint!($($arg)*);
        }
    };
}

/// `println!` for the command's report on stdout, where a reader that stops early
/// (`penumbra render | head -3`) is no error: the command still finishes its job (the image
/// is written) and the lines nobody reads are dropped. Other write errors go to stderr.
macro_rules! outln {
    () => {
        $crate::cli::write_stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cli::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` as [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::write_stdout(format_args!($($arg)*))
    };
}

/// Writes to stdout for [`outln!`] and [`out!`]: a closed pipe drops the text quietly.
pub fn write_stdout(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    match std::io::stdout().lock().write_fmt(args) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
        Err(e) => eprintln!("warning: writing to stdout: {e}"),
    }
}

/// Fails with [`penumbra::Error::Output`] naming `path` when the folder it would be written
/// into does not exist: commands check their output paths before the work, so that a
/// mistyped folder does not cost a whole render or a half-hour quality run.
pub fn check_output_folder(path: &std::path::Path) -> penumbra::Result<()> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if folder.is_dir() {
        return Ok(());
    }
    Err(penumbra::Error::Output {
        path: path.to_path_buf(),
        message: format!(
            "cannot write there: the folder {} does not exist",
            folder.display()
        ),
    })
}

mod bench;
mod compare;
mod exact;
mod info;
mod quality;
mod render;
mod scene_arg;

use clap::{Parser, Subcommand, ValueEnum};

use penumbra::bvh::{BuildQuality, BvhSettings};

/// Ray-traced soft shadows from area lights (multi-frusta tracing on wgpu).
#[derive(Debug, Parser)]
#[command(name = "penumbra", version, about)]
pub struct Cli {
    /// On an error, also print its source chain and full detail.
    #[arg(long, short, global = true)]
    pub verbose: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Load a scene, build its BVH and print statistics.
    Info(info::InfoArgs),
    /// Render a scene's soft shadows to PNG or EXR on the GPU and print timings.
    Render(render::RenderArgs),
    /// Time the shadow tracers against each other and count their work (Table 1).
    Bench(bench::BenchArgs),
    /// Error of MFT (filtered and not) and of the reference tracer against exact visibility.
    Quality(quality::QualityArgs),
    /// Compare two images (PNG or EXR): RMSE, mean and max absolute error, PSNR,
    /// and optionally a false-colour difference image.
    Compare(compare::CompareArgs),
}

/// BVH build options shared by the commands that build one.
#[derive(Debug, Clone, clap::Args)]
pub struct BvhArgs {
    /// Largest number of triangles per BVH leaf (1..=255).
    #[arg(long, default_value_t = BvhSettings::default().max_leaf_size, value_parser = clap::value_parser!(u32).range(1..=255))]
    pub leaf_size: u32,
    /// BVH build quality: build time against tree quality.
    #[arg(long, value_enum, default_value_t = QualityArg::High)]
    pub quality: QualityArg,
}

/// `--quality` values.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum QualityArg {
    /// Quick build (obvhs fast preset).
    Fast,
    /// Balanced (obvhs medium preset).
    Medium,
    /// Slowest build, best tree (obvhs slow preset, no pre-splits); the default.
    High,
}

impl BvhArgs {
    /// The library settings these flags select.
    pub fn settings(&self) -> BvhSettings {
        BvhSettings {
            max_leaf_size: self.leaf_size,
            quality: match self.quality {
                QualityArg::Fast => BuildQuality::Fast,
                QualityArg::Medium => BuildQuality::Medium,
                QualityArg::High => BuildQuality::High,
            },
        }
    }
}

/// Runs the chosen command.
pub fn run(cli: Cli) -> penumbra::Result<()> {
    match cli.command {
        Command::Info(args) => info::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Quality(args) => quality::run(&args),
        Command::Compare(args) => compare::run(&args),
    }
}

/// Writes `report` as pretty JSON to `path`, whole or not at all.
pub fn write_json(path: &std::path::Path, report: &impl serde::Serialize) -> penumbra::Result<()> {
    let json = serde_json::to_vec_pretty(report).map_err(|e| penumbra::Error::Output {
        path: path.to_owned(),
        message: format!("could not encode the report: {e}"),
    })?;
    penumbra::output::write_bytes_atomically(path, &json)
}

/// The text `main` prints for an error: one line `error: ...` (a multi-line
/// message joined with `; `); with `verbose`, followed by one `caused by: `
/// line per source in the error's chain and a `detail: ` line with its debug form.
pub fn error_report(err: &penumbra::Error, verbose: bool) -> String {
    let mut out = format!("error: {}", one_line(&err.to_string()));
    if verbose {
        let mut source = std::error::Error::source(err);
        while let Some(s) = source {
            out.push_str(&format!("\ncaused by: {}", one_line(&s.to_string())));
            source = s.source();
        }
        out.push_str(&format!("\ndetail: {err:?}"));
    }
    out
}

/// `text`'s non-empty lines, trimmed and joined with `; `.
fn one_line(text: &str) -> String {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// A panic payload as text (`panic!` gives a `&str` or a `String`).
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    let text = if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic with a non-text payload".to_owned()
    };
    one_line(&text)
}

/// Parses `WIDTHxHEIGHT` (both at least 1).
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 512x512")?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("'{v}': {e}"));
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 {
        return Err("width and height must be at least 1".into());
    }
    Ok((w, h))
}
