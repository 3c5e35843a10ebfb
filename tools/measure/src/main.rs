//! `sppm-measure bezier`: speed against accuracy of the Bezier intersectors and of meshes of
//! the same surfaces (a thin front for [`sppm_measure::bezier`]); `sppm-measure lights`:
//! direct-light noise of area lights sampled by area and by solid angle
//! ([`sppm_measure::lights`]); `sppm-measure coat` and `furnace`: directional albedos of the
//! rough coat and the rough metal lobe ([`sppm_measure::layered`]). Run from the repository root:
//! `cargo run --release -p sppm-measure -- bezier` (or `lights`). Exit status: 0 ok, 2 usage
//! errors.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Arg, ArgAction, ArgMatches, Command};
use sppm_measure::bezier::{Method, Options, run, write_outputs};

/// Usage errors (bad arguments, unwritable output), as in `sppm-lang`.
const EXIT_USAGE: u8 = 2;

pub struct BenchArgs {
    pub what: Bench,
}

pub enum Bench {
    Bezier(BezierArgs),
    Lights(LightsArgs),
    Cost(CostArgs),
    Twin(TwinArgs),
    Setup(SetupArgs),
    Coat(SamplesArgs),
    Furnace(SamplesArgs),
}

pub struct SamplesArgs {
    pub samples: u64,
}

pub struct SetupArgs {
    pub obj: PathBuf,
    pub threads: Vec<usize>,
    pub rounds: u32,
}

pub struct TwinArgs {
    pub scene: PathBuf,
    pub output: PathBuf,
    pub tolerance: f64,
}

pub struct LightsArgs {
    pub size: u32,
    pub rounds: u32,
    pub per_round: u32,
}

pub struct CostArgs {
    pub rays: u64,
    pub repeats: u64,
}

pub struct BezierArgs {
    pub output: PathBuf,
    pub rays: u64,
    pub repeats: u64,
    pub seed: u64,
}

/// `--long VALUE` with a default (clap's builder, as `sppm-lang` has it: no derive macros to
/// build).
fn option(
    id: &'static str,
    long: &'static str,
    value_name: &'static str,
    default: &'static str,
    help: &'static str,
) -> Arg {
    Arg::new(id)
        .long(long)
        .value_name(value_name)
        .action(ArgAction::Set)
        .default_value(default)
        .help(help)
}

/// A number option with a range.
fn ranged_u64(arg: Arg, range: std::ops::RangeInclusive<u64>) -> Arg {
    arg.value_parser(clap::value_parser!(u64).range(range))
}

/// A `u32` option with a range.
fn ranged_u32(arg: Arg, range: std::ops::RangeInclusive<i64>) -> Arg {
    arg.value_parser(clap::value_parser!(u32).range(range))
}

fn command() -> Command {
    let samples = || {
        ranged_u64(
            option(
                "samples",
                "samples",
                "SAMPLES",
                "1000000",
                "Samples (random walks) per table cell",
            ),
            100..=1_000_000_000,
        )
    };
    Command::new("sppm-measure")
        .about("Measurements of sppm-lang's own parts (speed against accuracy)")
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(
            Command::new("bezier")
                .about(
                    "Revolve and patch: robust, Newton settings and tessellated meshes against \
                     the reference intersector; ns per ray against miss rate and t error (CSV and \
                     charts)",
                )
                .arg(
                    option(
                        "output",
                        "output",
                        "OUTPUT",
                        "docs/charts/bezier.png",
                        "Overview chart (.png or .svg); the CSV, the single charts and the other \
                         format are written beside it with the same stem",
                    )
                    .short('o')
                    .value_parser(clap::value_parser!(PathBuf)),
                )
                .arg(ranged_u64(
                    option(
                        "rays",
                        "rays",
                        "RAYS",
                        "10000",
                        "Rays per ray kind (the revolve has three kinds, the patch two)",
                    ),
                    1..=10_000_000,
                ))
                .arg(ranged_u64(
                    option(
                        "repeats",
                        "repeats",
                        "REPEATS",
                        "3",
                        "Timed passes over the ray set; the median is reported",
                    ),
                    1..=1000,
                ))
                .arg(
                    option("seed", "seed", "SEED", "1", "Seed of the ray set")
                        .value_parser(clap::value_parser!(u64)),
                ),
        )
        .subcommand(
            Command::new("lights")
                .about(
                    "Sphere and square lights over a plane: per-point variance of direct light \
                     sampled by area and by solid angle, wall and CPU time per estimate, and the \
                     variance ratio at equal CPU time",
                )
                .arg(ranged_u32(
                    option(
                        "size",
                        "size",
                        "SIZE",
                        "64",
                        "Points per side of the grid on the plane",
                    ),
                    2..=2048,
                ))
                .arg(ranged_u32(
                    option(
                        "rounds",
                        "rounds",
                        "ROUNDS",
                        "32",
                        "Rounds (each sampler once per round, alternating which goes first)",
                    ),
                    1..=100_000,
                ))
                .arg(ranged_u32(
                    option(
                        "per_round",
                        "per-round",
                        "PER_ROUND",
                        "16",
                        "Estimates per point, sampler and round",
                    ),
                    2..=100_000,
                )),
        )
        .subcommand(
            Command::new("cost")
                .about(
                    "Cost per ray of the revolves and the patch as a ratio to a quad's, same \
                     rays, same run",
                )
                .arg(ranged_u64(
                    option("rays", "rays", "RAYS", "100000", "Rays per surface"),
                    1..=10_000_000,
                ))
                .arg(ranged_u64(
                    option(
                        "repeats",
                        "repeats",
                        "REPEATS",
                        "5",
                        "Timed passes (the median ratio is reported)",
                    ),
                    1..=1000,
                )),
        )
        .subcommand(
            Command::new("twin")
                .about(
                    "A scene's twin with every revolve replaced by a mesh at a given silhouette \
                     accuracy",
                )
                .arg(
                    Arg::new("scene")
                        .value_name("SCENE")
                        .required(true)
                        .value_parser(clap::value_parser!(PathBuf))
                        .help("The scene whose revolves are tessellated"),
                )
                .arg(
                    option(
                        "output",
                        "output",
                        "OUTPUT",
                        "target/twin",
                        "Where the twin scene and its OBJ files go",
                    )
                    .short('o')
                    .value_parser(clap::value_parser!(PathBuf)),
                )
                .arg(
                    option(
                        "tolerance",
                        "tolerance",
                        "TOLERANCE",
                        "0.001",
                        "Largest distance between mesh and surface, in world units",
                    )
                    .value_parser(clap::value_parser!(f64)),
                ),
        )
        .subcommand(
            Command::new("setup")
                .about(
                    "The set-up of a large OBJ mesh step by step (read, parse, triangles, BVH): \
                     wall and CPU time on each thread count, rounds alternating",
                )
                .arg(
                    Arg::new("obj")
                        .value_name("OBJ")
                        .required(true)
                        .value_parser(clap::value_parser!(PathBuf))
                        .help(
                            "The OBJ file (e.g. the scale bench's \
                             `target/scale/n1000000/mesh.obj`)",
                        ),
                )
                .arg(
                    option(
                        "threads",
                        "threads",
                        "THREADS",
                        "1,2",
                        "Thread counts, measured in turn within each round",
                    )
                    .action(ArgAction::Append)
                    .value_delimiter(',')
                    .value_parser(clap::value_parser!(usize)),
                )
                .arg(ranged_u32(
                    Arg::new("rounds")
                        .long("rounds")
                        .value_name("ROUNDS")
                        .action(ArgAction::Set)
                        .default_value("3"),
                    1..=20,
                )),
        )
        .subcommand(
            Command::new("coat")
                .about(
                    "Directional albedo of the rough coat against a random walk through the \
                     layer (Markdown table)",
                )
                .arg(samples()),
        )
        .subcommand(
            Command::new("furnace")
                .about(
                    "White-furnace albedo of the rough metal lobe over roughness and angle \
                     (Markdown table)",
                )
                .arg(samples()),
        )
}

/// A value the parser has made sure of (required, or with a default).
fn take<T: Clone + Send + Sync + 'static>(m: &mut ArgMatches, id: &str) -> Result<T, clap::Error> {
    m.remove_one::<T>(id).ok_or_else(|| {
        clap::Error::raw(
            clap::error::ErrorKind::MissingRequiredArgument,
            format!("the following required argument was not provided: {id}"),
        )
    })
}

fn parse_args() -> Result<BenchArgs, clap::Error> {
    let mut matches = command().get_matches();
    let Some((name, mut sub)) = matches.remove_subcommand() else {
        return Err(clap::Error::new(clap::error::ErrorKind::MissingSubcommand));
    };
    let m = &mut sub;
    let what = match name.as_str() {
        "bezier" => Bench::Bezier(BezierArgs {
            output: take(m, "output")?,
            rays: take(m, "rays")?,
            repeats: take(m, "repeats")?,
            seed: take(m, "seed")?,
        }),
        "lights" => Bench::Lights(LightsArgs {
            size: take(m, "size")?,
            rounds: take(m, "rounds")?,
            per_round: take(m, "per_round")?,
        }),
        "cost" => Bench::Cost(CostArgs {
            rays: take(m, "rays")?,
            repeats: take(m, "repeats")?,
        }),
        "twin" => Bench::Twin(TwinArgs {
            scene: take(m, "scene")?,
            output: take(m, "output")?,
            tolerance: take(m, "tolerance")?,
        }),
        "setup" => Bench::Setup(SetupArgs {
            obj: take(m, "obj")?,
            threads: m
                .remove_many("threads")
                .map(Iterator::collect)
                .unwrap_or_default(),
            rounds: take(m, "rounds")?,
        }),
        "coat" => Bench::Coat(SamplesArgs {
            samples: take(m, "samples")?,
        }),
        "furnace" => Bench::Furnace(SamplesArgs {
            samples: take(m, "samples")?,
        }),
        _ => return Err(clap::Error::new(clap::error::ErrorKind::InvalidSubcommand)),
    };
    Ok(BenchArgs { what })
}

fn main() -> ExitCode {
    match parse_args() {
        Ok(args) => run_bench(&args),
        Err(e) => e.exit(),
    }
}

/// Writes `text` to stdout; a closed pipe or any other write error is ignored.
fn out(text: &str) {
    let mut s = std::io::stdout().lock();
    let _ = s.write_all(text.as_bytes()).and_then(|()| s.flush());
}

/// Writes `text` to stderr; a closed pipe or any other write error is ignored.
fn err(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

fn run_bench(args: &BenchArgs) -> ExitCode {
    match &args.what {
        Bench::Bezier(a) => finish(bezier(a)),
        Bench::Cost(a) => finish(cost(a)),
        Bench::Twin(a) => finish(twin(a)),
        Bench::Lights(a) => finish(lights(a)),
        Bench::Setup(a) => finish(setup(a)),
        Bench::Coat(a) => {
            out(&sppm_measure::layered::coat_table(1.5, a.samples));
            ExitCode::SUCCESS
        }
        Bench::Furnace(a) => {
            out(&sppm_measure::layered::furnace_table(a.samples));
            ExitCode::SUCCESS
        }
    }
}

fn finish(r: Result<(), String>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            err(&format!("error: {e}\n"));
            ExitCode::from(EXIT_USAGE)
        }
    }
}

fn setup(args: &SetupArgs) -> Result<(), String> {
    if args.threads.iter().any(|&t| t == 0 || t > 256) {
        return Err("--threads takes counts from 1 to 256".into());
    }
    for round in 1..=args.rounds {
        for &threads in &args.threads {
            let steps = sppm_measure::setup::run(&args.obj, threads)?;
            let mut text = format!("round {round}, {threads} thread(s):\n");
            let (mut wall, mut cpu) = (0.0, 0.0);
            for s in &steps {
                let _ = writeln!(
                    text,
                    "  {:<34} {:7.3} s wall {:7.3} s CPU",
                    s.name, s.wall, s.cpu
                );
                if sppm_measure::setup::counted(s) {
                    wall += s.wall;
                    cpu += s.cpu;
                }
            }
            let _ = writeln!(
                text,
                "  {:<34} {wall:7.3} s wall {cpu:7.3} s CPU",
                "total (steps not in parentheses)"
            );
            out(&text);
        }
    }
    Ok(())
}

fn twin(args: &TwinArgs) -> Result<(), String> {
    if !(args.tolerance > 0.0 && args.tolerance.is_finite()) {
        return Err("--tolerance must be a positive number".into());
    }
    let (lines, path) = sppm_measure::twin::write_twin(&args.scene, &args.output, args.tolerance)?;
    for l in lines {
        out(&format!("{l}\n"));
    }
    out(&format!("wrote {path}\n"));
    Ok(())
}

fn cost(args: &CostArgs) -> Result<(), String> {
    let rows = sppm_measure::cost::run(args.rays as usize, args.repeats as usize)?;
    let mut table = format!(
        "{:<16} {:>9} {:>9} {:>9}\n",
        "surface", "ns/ray", "x quad", "hit rate"
    );
    for r in rows {
        let _ = writeln!(
            table,
            "{:<16} {:>9.0} {:>9.2} {:>9.3}",
            r.name, r.ns_per_ray, r.vs_quad, r.hit_rate
        );
    }
    out(&table);
    Ok(())
}

fn lights(args: &LightsArgs) -> Result<(), String> {
    use sppm_lang::internals::lights::LightSampling;
    let rows = sppm_measure::lights::run(args.size, args.rounds, args.per_round, &|line| {
        err(&format!("lights: {line}\n"))
    })?;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "{:<7} {:<12} {:>12} {:>10} {:>10} {:>10} {:>12}",
        "scene", "sampling", "variance", "mean", "wall ns", "cpu ns", "x at equal t"
    );
    for r in &rows {
        let area = rows
            .iter()
            .find(|a| a.scene == r.scene && a.sampling == LightSampling::Area)
            .map_or(f64::NAN, |a| a.variance_times_time());
        let _ = writeln!(
            table,
            "{:<7} {:<12} {:>12.4e} {:>10.5} {:>10.0} {:>10.0} {:>12.2}",
            r.scene,
            format!("{:?}", r.sampling),
            r.variance,
            r.mean,
            r.wall_per_estimate * 1e9,
            r.cpu_per_estimate * 1e9,
            area / r.variance_times_time(),
        );
    }
    out(&table);
    Ok(())
}

fn bezier(args: &BezierArgs) -> Result<(), String> {
    let ext = args.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("svg")) {
        return Err(format!(
            "output `{}` must end in .png or .svg",
            args.output.display()
        ));
    }
    let mut opts = Options::full(args.rays as usize);
    opts.repeats = args.repeats as usize;
    opts.seed = args.seed;
    let rows = run(&opts, &|line| err(&format!("bench bezier: {line}\n")))?;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "{:<8} {:<16} {:>9} {:>9} {:>8} {:>9} {:>9} {:>6} {:>10} {:>10}",
        "surface",
        "method",
        "triangles",
        "ns/ray",
        "x robust",
        "miss",
        "false hit",
        "far",
        "t err med",
        "t err max"
    );
    for r in rows.iter().filter(|r| r.kind == "all") {
        let _ = writeln!(
            table,
            "{:<8} {:<16} {:>9} {:>9.0} {:>8.3} {:>9.2e} {:>9.2e} {:>6} {:>10.2e} {:>10.2e}",
            r.surface.name(),
            r.method.label(),
            if r.method == Method::Robust || matches!(r.method, Method::Newton { .. }) {
                String::new()
            } else {
                r.triangles.to_string()
            },
            r.ns_per_ray,
            r.time_vs_robust,
            r.miss_rate(),
            r.false_hit_rate(),
            r.far_hits,
            r.t_err_median,
            r.t_err_max,
        );
    }
    out(&table);
    for p in write_outputs(&rows, &args.output)? {
        err(&format!("wrote {}\n", p.display()));
    }
    Ok(())
}
