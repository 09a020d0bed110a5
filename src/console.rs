//! Standard output and error as a command-line tool must write them: never a panic. `println!`
//! panics when stdout is a closed pipe (`convshadow diff a b | head -1`) or a full device, and
//! `eprintln!` when stderr is; [`outln!`](crate::outln) and [`errln!`](crate::errln) write the
//! same text and record what failed instead.
//!
//! Policy (docs/errors.md): a reader that went away (a closed pipe) is not an error — the command
//! stops writing to stdout and keeps its exit code (a CI gate piping `diff` into `head` still
//! gets `diff`'s verdict); any other stdout failure (a full device, an I/O error) lost output,
//! so a command that would exit 0 exits 7 instead ([`final_code`]); a stderr that cannot be
//! written is ignored (the exit code still says what happened).

use std::fmt;
use std::io::Write;
use std::sync::Mutex;

/// The first stdout failure, if any: `Some(None)` for a closed pipe, `Some(Some(message))` for
/// an error that lost output.
static STDOUT_FAILED: Mutex<Option<Option<String>>> = Mutex::new(None);

/// Writes `args` (and a newline when `newline`) to stdout and flushes it; after the first
/// failure, writes nothing more. Use [`outln!`](crate::outln) / [`out!`](crate::out).
pub fn write_out(args: fmt::Arguments<'_>, newline: bool) {
    let mut failed = STDOUT_FAILED.lock().unwrap_or_else(|e| e.into_inner());
    if failed.is_some() {
        return;
    }
    if let Err(e) = write_to(&mut std::io::stdout().lock(), args, newline) {
        *failed = Some(if e.kind() == std::io::ErrorKind::BrokenPipe {
            None
        } else {
            Some(e.to_string())
        });
    }
}

/// Writes `args` (and a newline when `newline`) to stderr, ignoring failures. Use
/// [`errln!`](crate::errln) / [`err!`](crate::err).
pub fn write_err(args: fmt::Arguments<'_>, newline: bool) {
    let _ = write_to(&mut std::io::stderr().lock(), args, newline);
}

/// `args`, a newline when `newline`, then a flush (so that a full device fails here, not later).
fn write_to(w: &mut impl Write, args: fmt::Arguments<'_>, newline: bool) -> std::io::Result<()> {
    w.write_fmt(args)?;
    if newline {
        w.write_all(b"\n")?;
    }
    w.flush()
}

/// The exit code of a command that would exit with `code`, given what stdout did: 7 (output
/// failed) instead of 0 when stdout failed other than by a closed pipe (saying so on stderr);
/// else `code`.
pub fn final_code(code: i32) -> i32 {
    let failed = STDOUT_FAILED
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .clone();
    match failed {
        Some(Some(message)) if code == 0 => {
            write_err(format_args!("error: standard output: {message}"), true);
            OUTPUT_FAILED
        }
        _ => code,
    }
}

/// The CLI's exit code for an output that could not be written (`src/cli/exit.rs`).
pub const OUTPUT_FAILED: i32 = 7;

/// `println!` that never panics (see the [module](crate::console)).
#[macro_export]
macro_rules! outln {
    () => { $crate::console::write_out(format_args!(""), true) };
    ($($t:tt)*) => { $crate::console::write_out(format_args!($($t)*), true) };
}

/// `print!` that never panics (see the [module](crate::console)).
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::console::write_out(format_args!($($t)*), false) };
}

/// `eprintln!` that never panics (see the [module](crate::console)).
#[macro_export]
macro_rules! errln {
    () => { $crate::console::write_err(format_args!(""), true) };
    ($($t:tt)*) => { $crate::console::write_err(format_args!($($t)*), true) };
}

/// `eprint!` that never panics (see the [module](crate::console)).
#[macro_export]
macro_rules! err {
    ($($t:tt)*) => { $crate::console::write_err(format_args!($($t)*), false) };
}
