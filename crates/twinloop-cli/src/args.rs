//! The command line parsed, and what every command shares checked before any work:
//! its outputs (crate::outputs) and its counts (crate::bounds). Kept out of `common`,
//! which `bounds` uses, so that the two do not import each other.

/// Parse the command line. Every command takes a negative number as an option's value
/// (`--dt -1`), so that the option's range check says what is wrong and names it,
/// instead of clap reading "-1" as an unknown flag.
pub fn parse_args<C: clap::Parser>() -> C {
    fn allow_negative(c: clap::Command) -> clap::Command {
        c.allow_negative_numbers(true)
            .mut_subcommands(allow_negative)
    }
    let cli = allow_negative(C::command());
    let matches = cli.clone().get_matches();
    // The outputs are checked before any work (crate::outputs): exit 2, one line.
    if let Err(e) = crate::outputs::check(&cli, &matches)
        .and_then(|()| crate::bounds::check_counts(&cli, &matches))
        .and_then(|()| check_lists(&cli, &matches))
    {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    C::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// Every comma-separated option (`--frames a,b`, `--inputs u:a,u:b`) holds no empty
/// item: `a,,b`, `a,` or `,b` is a typo (a name lost, or one left out), refused naming
/// the option and the item, never read as a list one shorter or an item named "".
fn check_lists(
    cli: &clap::Command,
    matches: &clap::ArgMatches,
) -> Result<(), crate::error::CliError> {
    let Some((cmd, m)) = crate::bounds::leaf(cli, matches) else {
        return Ok(());
    };
    for arg in cmd.get_arguments() {
        let (Some(long), Some(sep)) = (arg.get_long(), arg.get_value_delimiter()) else {
            continue;
        };
        let Ok(Some(values)) = m.try_get_raw(arg.get_id().as_str()) else {
            continue;
        };
        let items: Vec<String> = values.map(|v| v.to_string_lossy().into_owned()).collect();
        if let Some(k) = items.iter().position(|v| v.trim().is_empty()) {
            return Err(crate::error::CliError::new(format!(
                "--{long} {}: item {} is empty; write the items between '{sep}'s, none left out",
                items.join(&sep.to_string()),
                k + 1
            )));
        }
    }
    Ok(())
}
