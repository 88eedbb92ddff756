//! The commands the documentation shows with their output (a ```sh block followed directly by a
//! plain ``` block, in README.md and docs/*.md) print that output when run as written: the numbers
//! in the docs come from the tool, and cannot drift from it. Times (`in 1.06 s`) are left out of the
//! comparison.

mod common;

use common::{BIN, assert_success};
use std::path::{Path, PathBuf};
use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Every (file, commands, output) the docs show: the `implicit-psdr` lines of the sh block (with
/// `\` continuations joined) and the lines of the output block.
fn shown() -> Vec<(PathBuf, Vec<String>, Vec<String>)> {
    let mut files = vec![Path::new(ROOT).join("README.md")];
    for entry in std::fs::read_dir(Path::new(ROOT).join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            files.push(path);
        }
    }
    let mut out = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        for (k, block) in text.split("```sh\n").enumerate().skip(1) {
            let Some((commands, rest)) = block.split_once("```\n") else {
                panic!("{}: sh block {k} is not closed", file.display());
            };
            let Some(output) = rest.strip_prefix("```\n") else {
                continue;
            };
            let output = output.split("```").next().unwrap();
            let commands = commands.replace("\\\n", " ");
            let commands = (commands.lines())
                .filter_map(|l| l.trim().strip_prefix("implicit-psdr "))
                .map(String::from)
                .collect();
            let output = output.lines().map(String::from).collect();
            out.push((file.clone(), commands, output));
        }
    }
    out
}

/// `line` with the number of every `in N s` replaced by `_`.
fn without_times(line: &str) -> String {
    let words: Vec<&str> = line.split(' ').collect();
    let masked: Vec<&str> = (0..words.len())
        .map(|i| {
            let timed = i > 0
                && words[i - 1] == "in"
                && words.get(i + 1).is_some_and(|w| w.starts_with('s'))
                && words[i].parse::<f64>().is_ok();
            if timed { "_" } else { words[i] }
        })
        .collect();
    masked.join(" ")
}

#[test]
fn the_docs_outputs_are_the_tools() {
    let shown = shown();
    assert!(!shown.is_empty(), "no command with its output in the docs");
    for (n, (file, commands, expected)) in shown.into_iter().enumerate() {
        // A fresh folder that sees the repository's scenes where the docs' commands look for them.
        let dir = common::workdir("docs", &n.to_string());
        std::os::unix::fs::symlink(Path::new(ROOT).join("scenes"), dir.join("scenes")).unwrap();
        let mut last = String::new();
        for command in &commands {
            let args: Vec<&str> = command.split_whitespace().collect();
            let out = Command::new(BIN)
                .args(&args)
                .current_dir(&dir)
                .output()
                .unwrap();
            last = assert_success(&out);
        }
        let got: Vec<String> = last.lines().map(without_times).collect();
        let want: Vec<String> = expected.iter().map(|l| without_times(l)).collect();
        assert_eq!(got, want, "{}: the output of {commands:?}", file.display());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn times_are_masked_and_nothing_else() {
    assert_eq!(
        without_times("rendered 8x8 in 1.06 s; wrote in 3 files"),
        "rendered 8x8 in _ s; wrote in 3 files"
    );
}
