//! The Python module's tests (python/tests, pytest) under `cargo test`: builds the module
//! with `pip install ./python` into a virtual environment in target/ (with pytest, numpy
//! and pyoidn, whose wheel ships Open Image Denoise), then runs pytest there with this
//! build's `wgtrace` binary. Needs python3 with venv (`apt-get install python3-venv`) and
//! the network for the first run; fails, never skips, without them.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(cmd: &mut Command, what: &str) {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed ({cmd:?}):\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_python_module_passes_its_tests() {
    let venv = root().join("target").join("python-venv");
    let python = venv.join("bin").join("python");
    if !python.exists() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "creating a virtual environment (apt-get install python3-venv)",
        );
    }
    let pip = |args: &[&str], what: &str| {
        run(
            Command::new(&python)
                .args([
                    "-m",
                    "pip",
                    "install",
                    "--quiet",
                    "--disable-pip-version-check",
                ])
                .args(args)
                // the same target folder as `cargo test`'s (which holds no lock on it
                // while tests run), so the module's build reuses the library's
                // compiled dependencies
                .env("CARGO_TARGET_DIR", root().join("target"))
                .current_dir(root()),
            what,
        )
    };
    pip(
        &["pytest", "numpy", "pyoidn"],
        "installing pytest, numpy and pyoidn",
    );
    pip(
        &["--force-reinstall", "--no-deps", "./python"],
        "pip install ./python",
    );
    let bin = Path::new(env!("CARGO_BIN_EXE_wgtrace"));
    let out = Command::new(&python)
        .args(["-m", "pytest", "-q", "-rA", "python/tests"])
        .env("WGTRACE_BIN", bin)
        .current_dir(root())
        .output()
        .expect("run pytest");
    let text = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "pytest failed:\n{text}");
}
