//! `skinkit`: the command-line face of the skinkit libraries.
//!
//! This crate only parses arguments, turns them into validated library configs, draws progress on
//! stderr and prints results; the work itself lives in the library crates. Exit codes: 0 when all
//! went well, 1 when an input or the job failed (a bad photo, rig or session, an unwritable
//! output), 2 for a usage error, 130 when interrupted (SIGINT, SIGTERM or SIGHUP; see
//! `interrupt`). Errors print as one line ([`output::Output::error`]), each cause once.

mod cmd;
mod face;
mod flags;
mod interrupt;
mod machine;
mod output;
mod pipeline;
mod render_job;
mod solve_flags;

use clap::{Parser, Subcommand};

/// Capture, grow and render fine-scale human skin structure.
#[derive(Parser, Debug)]
#[command(name = "skinkit", version, about, propagate_version = true)]
struct Cli {
    #[command(flatten)]
    global: output::GlobalArgs,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Photometric stereo: photos of a mold under known lights -> normal, albedo and confidence maps.
    Capture(cmd::capture::Args),
    /// Light rigs: import from public formats, calibrate from sphere photos, check conditioning.
    #[command(subcommand)]
    Rig(cmd::rig::Command),
    /// Capture every session (sub-folder with photos and rig.toml) of a folder, in parallel.
    Batch(cmd::batch::Args),
    /// Regenerate the bundled sample molds (rendered from synthetic skin heightfields).
    Samples(cmd::samples::Args),
    /// Run the whole pipeline on the bundled samples (capture, growth, face) and report its accuracy.
    Demo(cmd::demo::Args),
    /// Grow a normal or colour map from an exemplar (Wei-Levoy); `synth replay` copies another
    /// map through the coordinate map of a run.
    #[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
    Synth(Box<cmd::synth::Args>),
    /// Stitch one synthesis per face region into a face normal map (multiresolution spline along
    /// random curves).
    Stitch(cmd::stitch::StitchArgs),
    /// Capture, grow and stitch a face layout in one go into a folder of maps and a report.
    Face(cmd::stitch::FaceArgs),
    /// Integrate a normal map into a height (displacement) map in millimetres, with the 16-bit
    /// PNG, cavity and band files artists load.
    Height(cmd::height::Args),
    /// Render a scene (mesh, maps, Lafortune skin, lights, cameras) with the bundled wgpu renderer.
    Render(cmd::render::Args),
    /// Export a scene's skin for other tools (glTF 2.0: mesh, tangents, albedo, normal map, roughness).
    #[command(subcommand)]
    Export(cmd::export::Command),
    /// Build a pre-integrated skin table (diffuse falloff or shadow scattering) as a float EXR.
    #[command(subcommand)]
    Lut(cmd::lut::Command),
    /// Measure every stage's choices against ground truth and what each costs in time.
    Accuracy(cmd::accuracy::Args),
    /// Open a scene in the interactive viewer (orbit, move the light, toggle the normal map and
    /// specular); built with `--features viewer`.
    #[cfg(feature = "viewer")]
    View(cmd::render::ViewArgs),
}

fn main() {
    // SAFETY: the first statement of `main`, before any thread is started.
    unsafe { skinkit_render::renderer::quiet_vulkan_loader() };
    let cli = Cli::parse();
    interrupt::install();
    let out = output::Output::new(&cli.global);
    let result = match cli.command {
        Command::Capture(args) => cmd::capture::run(args, &out),
        Command::Rig(command) => cmd::rig::run(command, &out),
        Command::Batch(args) => cmd::batch::run(args, &out),
        Command::Samples(args) => cmd::samples::run(args, &out),
        Command::Demo(args) => cmd::demo::run(args, &out),
        Command::Synth(args) => cmd::synth::run(*args, &out),
        Command::Stitch(args) => cmd::stitch::run_stitch(args, &out),
        Command::Face(args) => cmd::stitch::run_face(args, &out),
        Command::Height(args) => cmd::height::run(args, &out),
        Command::Render(args) => cmd::render::run(args, &out),
        Command::Export(command) => cmd::export::run(command, &out),
        Command::Lut(command) => cmd::lut::run(command, &out),
        Command::Accuracy(args) => cmd::accuracy::run(args, &out),
        #[cfg(feature = "viewer")]
        Command::View(args) => cmd::render::view(args, &out),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(error) => {
            out.error(&error);
            std::process::exit(output::exit_code(&error));
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_consistent() {
        super::Cli::command().debug_assert();
    }

    /// Every value-taking flag of every subcommand, with the command it belongs to.
    fn flags(command: &clap::Command, path: &str, found: &mut Vec<(String, clap::Arg)>) {
        for arg in command.get_arguments().filter(|a| a.get_action().takes_values()) {
            found.push((format!("{path} --{}", arg.get_id()), arg.clone()));
        }
        for sub in command.get_subcommands() {
            flags(sub, &format!("{path} {}", sub.get_name()), found);
        }
    }

    /// Issue 42: no numeric flag takes a value it cannot mean. A number that is not finite, or
    /// one beyond any size a run can have, is a usage error for every flag, found here by
    /// walking the whole command line (a new flag is checked without being listed).
    #[test]
    fn no_flag_accepts_a_number_it_cannot_mean() {
        let mut all = Vec::new();
        flags(&super::Cli::command(), "skinkit", &mut all);
        assert!(all.len() > 50, "only {} flags found", all.len());
        let absurd = ["nan", "inf", "-inf", "1e30", "-1e30", "18446744073709551615"];
        let mut accepted = Vec::new();
        for (name, arg) in &all {
            let parser = arg.get_value_parser();
            // A seed is any 64-bit number.
            if takes_text(parser) || arg.get_id() == "seed" {
                continue;
            }
            // The flag alone, with its parser, so that no other flag's rules interfere.
            let alone = clap::Command::new("t")
                .arg(clap::Arg::new("v").long("v").value_parser(parser.clone()).action(clap::ArgAction::Set));
            for value in absurd {
                if alone.clone().try_get_matches_from(["t", "--v", value]).is_ok() {
                    accepted.push(format!("{name} {value}"));
                }
            }
        }
        assert!(accepted.is_empty(), "flags accept numbers they cannot mean:\n{}", accepted.join("\n"));
    }

    /// Whether a flag's values are text or paths (any spelling is a valid value of those).
    fn takes_text(parser: &clap::builder::ValueParser) -> bool {
        let id = parser.type_id();
        [
            clap::builder::ValueParser::string().type_id(),
            clap::builder::ValueParser::path_buf().type_id(),
            clap::builder::ValueParser::os_string().type_id(),
        ]
        .contains(&id)
    }
}
