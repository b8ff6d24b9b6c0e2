//! The integrators' parameters as command-line flags, made from the registry: every parameter
//! some integrator has becomes `--name-with-dashes VALUE`, its help taken from the
//! `ParamSpec`, so a new parameter needs no edit in app/. Values are checked where they take
//! effect (`Session::start`), against the chosen integrator's ranges.

use caustica_renderer::integrators::{self, ParamSpec, ParamValues};
use clap::{Arg, ArgMatches, Args, Command, FromArgMatches};

/// The integrator parameters given on the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamFlags {
    pub given: ParamValues,
}

/// The flag of parameter `name`: `max_depth` is `--max-depth`.
pub fn flag_of(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}

/// Each parameter name once, with every integrator that has it and its spec there.
fn parameters() -> Vec<(&'static str, Vec<(&'static str, &'static ParamSpec)>)> {
    let mut out: Vec<(&'static str, Vec<(&'static str, &'static ParamSpec)>)> = Vec::new();
    for info in integrators::registry() {
        for spec in info.params {
            match out.iter_mut().find(|(name, _)| *name == spec.name) {
                Some((_, users)) => users.push((info.name, spec)),
                None => out.push((spec.name, vec![(info.name, spec)])),
            }
        }
    }
    out
}

/// Help of one flag: its description (each integrator's where they differ, as `radius`'s
/// automatic choice does), then which integrators read it and their defaults (`max_depth`: 64
/// for the path tracers, 10 for MMLT).
fn help(users: &[(&'static str, &'static ParamSpec)]) -> String {
    let mut docs: Vec<(Vec<&str>, &str)> = Vec::new();
    for (integrator, spec) in users {
        match docs.iter_mut().find(|(_, d)| *d == spec.doc) {
            Some((names, _)) => names.push(integrator),
            None => docs.push((vec![integrator], spec.doc)),
        }
    }
    let doc = match docs.as_slice() {
        [(_, doc)] => doc.to_string(),
        _ => docs
            .iter()
            .map(|(names, doc)| format!("{}: {doc}", names.join(", ")))
            .collect::<Vec<_>>()
            .join(" "),
    };
    let mut groups: Vec<(Vec<&str>, f64)> = Vec::new();
    for (integrator, spec) in users {
        match groups.iter_mut().find(|(_, d)| *d == spec.default) {
            Some((names, _)) => names.push(integrator),
            None => groups.push((vec![integrator], spec.default)),
        }
    }
    let defaults: Vec<String> = groups
        .iter()
        .map(|(names, d)| format!("{}: default {d}", names.join(", ")))
        .collect();
    format!("{doc} [{}]", defaults.join("; "))
}

fn parse_number(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("'{s}' is not a number"))
}

impl Args for ParamFlags {
    fn augment_args(cmd: Command) -> Command {
        parameters().into_iter().fold(cmd, |cmd, (name, users)| {
            cmd.arg(
                Arg::new(name)
                    .long(name.replace('_', "-"))
                    .value_name("V")
                    .value_parser(parse_number)
                    .allow_negative_numbers(true)
                    .help(help(&users)),
            )
        })
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for ParamFlags {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = ParamFlags::default();
        flags.update_from_arg_matches(matches)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        for (name, _) in parameters() {
            if let Some(v) = matches.get_one::<f64>(name) {
                self.given.insert(name.to_string(), *v);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        params: ParamFlags,
    }

    #[test]
    fn every_registered_parameter_is_a_flag() {
        let cli = Cli::try_parse_from(["x", "--max-depth", "5", "--sigma", "0.02"]).unwrap();
        let expected = ParamValues::from([("max_depth".into(), 5.0), ("sigma".into(), 0.02)]);
        assert_eq!(cli.params.given, expected);
        let help = Cli::command().render_long_help().to_string();
        for info in integrators::registry() {
            for spec in info.params {
                assert!(
                    help.contains(&flag_of(spec.name)),
                    "no flag for {}",
                    spec.name
                );
            }
        }
        // Every integrator with max_depth shares its default of 64 (the registry's order).
        let with_depth: Vec<&str> = integrators::registry()
            .iter()
            .filter(|i| i.params.iter().any(|p| p.name == "max_depth"))
            .map(|i| i.name)
            .collect();
        assert!(with_depth.len() >= 9, "{with_depth:?}");
        assert!(
            help.contains(&format!("[{}: default 64]", with_depth.join(", "))),
            "{help}"
        );
        // Where integrators describe a parameter differently, each description is shown.
        assert!(
            help.contains("ppm, sppm, pppm, amcppm: Initial gather radius")
                && help.contains("vcm: Merge radius"),
            "{help}"
        );
        assert!(Cli::try_parse_from(["x", "--alpha", "many"]).is_err());
    }
}
