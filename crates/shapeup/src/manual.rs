//! `shapeup completions SHELL` and `shapeup man`: shell completions (clap_complete) and manual
//! pages (clap_mangen), generated from the same clap definition as `--help`, so they never
//! drift from the command line.

use crate::Cli;
use anyhow::{Context, Result};
use clap::CommandFactory;
use shapeup_core::io::{create_output_folder, write_atomic};
use std::io::Write;
use std::path::Path;

/// The completion script for `shell`, on stdout.
pub fn completions(shell: clap_complete::Shell) -> Result<()> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "shapeup", &mut script);
    std::io::stdout().lock().write_all(&script)?;
    Ok(())
}

/// Every manual page: `shapeup.1`, then one per subcommand (`shapeup-deform.1`, …, nested ones
/// too), as (file name, roff text).
fn pages() -> Result<Vec<(String, Vec<u8>)>> {
    fn collect(cmd: &clap::Command, pages: &mut Vec<(String, Vec<u8>)>) -> Result<()> {
        let man = clap_mangen::Man::new(cmd.clone());
        let mut text = Vec::new();
        man.render(&mut text)?;
        pages.push((man.get_filename(), text));
        for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
            collect(sub, pages)?;
        }
        Ok(())
    }
    // Built once so that subcommands carry their display names (shapeup-deform); no `help`
    // subcommand page.
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    let mut pages = Vec::new();
    collect(&cmd, &mut pages)?;
    Ok(pages)
}

/// `shapeup man`: `shapeup.1` on stdout, or with `output` every page written into that folder
/// (created if missing), each atomically.
pub fn man(output: Option<&Path>) -> Result<()> {
    let pages = pages()?;
    let mut out = std::io::stdout().lock();
    let Some(dir) = output else {
        let (_, main_page) = pages.first().context("no manual page")?;
        out.write_all(main_page)?;
        return Ok(());
    };
    // The folder is created; the folders above it must exist (the rule of every output).
    create_output_folder(dir)?;
    for (name, text) in &pages {
        let path = dir.join(name);
        write_atomic(&path, |w| w.write_all(text))?;
        writeln!(out, "wrote {}", shapeup_core::io::one_line(path.display()))?;
    }
    Ok(())
}
