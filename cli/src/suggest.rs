//! The command line parsed, with a suggestion clap does not make: a
//! command name with two letters swapped (`ppmc rnu`), which clap's
//! similarity measure scores too low to name.

use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::Parser;

/// `P` from the process's arguments, under the program's own name (a
/// board team's binary is not `ppmc`: [`ppmc::program`]), or exits as clap
/// does, with a tip naming the nearest command where clap has none.
pub(crate) fn parse<P: Parser>() -> P {
    let name = ppmc::program();
    let mut command = P::command().name(name.clone()).bin_name(name);
    let parsed = command
        .try_get_matches_from_mut(std::env::args_os())
        .and_then(|m| P::from_arg_matches(&m))
        .map_err(|e| e.format(&mut command));
    match parsed {
        Ok(p) => p,
        Err(mut e) => {
            if e.kind() == ErrorKind::InvalidSubcommand
                && e.get(ContextKind::SuggestedSubcommand).is_none()
            {
                if let Some(ContextValue::String(typed)) = e.get(ContextKind::InvalidSubcommand) {
                    let names: Vec<String> = P::command()
                        .get_subcommands()
                        .map(|c| c.get_name().to_string())
                        .collect();
                    if let Some(near) = nearest(typed, &names) {
                        e.insert(
                            ContextKind::SuggestedSubcommand,
                            ContextValue::Strings(vec![near]),
                        );
                    }
                }
            }
            e.exit()
        }
    }
}

/// The one name of `names` within two edits of `typed` (a letter added,
/// dropped, changed, or two neighbours swapped), the nearest if several.
fn nearest(typed: &str, names: &[String]) -> Option<String> {
    names
        .iter()
        .map(|n| (distance(typed, n), n))
        .filter(|(d, _)| *d <= 2 && *d < typed.chars().count())
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| n.clone())
}

/// Optimal string alignment distance: Levenshtein's, with a swap of two
/// neighbouring letters as one edit.
fn distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    d[0] = (0..=b.len()).collect();
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_swap_a_slip_and_nothing_near() {
        let names: Vec<String> = ["run", "report", "record", "judge"]
            .map(String::from)
            .to_vec();
        assert_eq!(nearest("rnu", &names).as_deref(), Some("run"));
        assert_eq!(nearest("jduge", &names).as_deref(), Some("judge"));
        assert_eq!(nearest("reprot", &names).as_deref(), Some("report"));
        assert_eq!(nearest("xyzzy", &names), None);
        // Two letters are not a guess at anything.
        assert_eq!(nearest("ab", &names), None);
    }
}
