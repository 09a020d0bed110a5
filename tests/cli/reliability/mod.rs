//! Reliability of the `convshadow` binary: every bad input is refused with a message
//! naming the problem and a documented exit code (docs/errors.md), nothing panics, no output or
//! temporary file is left behind, memory limits are enforced before allocating, and SIGINT/SIGTERM
//! stop a render cleanly with exit code 130.

use crate::support;
use crate::support::files_in;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod bad_input;
mod memory;
mod signals;

/// Also used by the budget property tests and the VDB tests.
pub(crate) use memory::run_measured;

/// Exit codes (docs/errors.md).
const BAD_INPUT: i32 = 3;

const RESOURCE_LIMIT: i32 = 4;

const OUTPUT_FAILED: i32 = 7;

const INTERRUPTED: i32 = 130;

/// The valid scene every file of tests/data/bad/ is derived from (one change each).
const BASE_SCENE: &str = r#"
[image]
width = 32
height = 32
[camera]
direction = [0.3, -0.2, 1.0]
view_width = 3.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[light]]
tilt_deg = [20.0, 10.0]
variance = [0.01, 0.02]
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
opacity = 0.5
"#;

/// Asserts a refused run: the exit code, no panic, the message names `what`.
fn assert_refused(name: &str, code: i32, expected_code: i32, err: &str, what: &[&str]) {
    assert!(!err.contains("panicked"), "{name}: must not panic:\n{err}");
    assert_eq!(code, expected_code, "{name}: exit code; stderr:\n{err}");
    assert!(err.starts_with("error: "), "{name}: one error line: {err}");
    assert!(
        !err.contains("  "),
        "{name}: a broken line continuation: {err}"
    );
    for w in what {
        assert!(err.contains(w), "{name}: message must name {w:?}: {err}");
    }
}
