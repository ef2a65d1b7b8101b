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
    {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    C::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}
