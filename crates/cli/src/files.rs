//! The files a command reads and writes, and the rule that no command overwrites one of its
//! own inputs.
//!
//! Every subcommand's arguments implement [`NamesFiles`]: they list their input files and
//! their outputs (files, or directories the command fills), each with the option that named
//! it. `main` checks the list with [`Files::check`] before the command reads anything, so a
//! new command gets the protection by implementing the trait (it cannot be dispatched
//! without it):
//!
//! ```ignore
//! impl NamesFiles for Args {
//!     fn files(&self) -> Files<'_> {
//!         Files::new()
//!             .input("--model", &self.model)
//!             .input("--desired", &self.desired)
//!             .output("--output", &self.output)
//!     }
//! }
//! ```
//!
//! Two paths are the same file when they resolve to the same canonical path (following
//! symbolic links, `..` and the like) or, on Unix, to the same device and inode (hard links).
//! An output that does not exist yet is resolved through its folder.

use std::borrow::Cow;
use std::path::{Component, Path, PathBuf};

use crate::CliError;

/// The files of one run of a command, each named by the option that gave it.
#[derive(Debug, Default)]
pub struct Files<'a> {
    inputs: Vec<(&'static str, Cow<'a, Path>)>,
    outputs: Vec<(&'static str, &'a Path, Kind)>,
}

/// What an output path is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// One file, replaced (atomically) by the command.
    File,
    /// A directory the command creates files in.
    Directory,
}

/// The arguments of a command that reads or writes files: every subcommand implements it.
pub trait NamesFiles {
    /// The inputs and outputs of this run.
    fn files(&self) -> Files<'_>;
}

impl<'a> Files<'a> {
    /// No files.
    pub fn new() -> Self {
        Self::default()
    }

    /// An input file named by `option` (e.g. `"--model"`).
    pub fn input(mut self, option: &'static str, path: &'a Path) -> Self {
        self.inputs.push((option, Cow::Borrowed(path)));
        self
    }

    /// An optional stage file (`--stage`): an input, and so is the model file it names
    /// (`hysteresis.mpim.model_file`, relative to the stage file), which the command reads as
    /// well. A stage file that cannot be read names nothing more (the command then says why).
    pub fn stage(mut self, option: &'static str, path: Option<&'a PathBuf>) -> Self {
        let Some(path) = path else {
            return self;
        };
        self.inputs.push((option, Cow::Borrowed(path.as_path())));
        if let Ok(config) = hystcomp_stage::StageConfig::from_toml_file(path)
            && let Some(model) = config.hysteresis.mpim.model_file
        {
            self.inputs.push((
                "the stage file's hysteresis.mpim.model_file",
                Cow::Owned(model),
            ));
        }
        self
    }

    /// An optional input file.
    pub fn maybe_input(self, option: &'static str, path: Option<&'a PathBuf>) -> Self {
        match path {
            Some(path) => self.input(option, path),
            None => self,
        }
    }

    /// An output file named by `option` (e.g. `"--output"`).
    pub fn output(mut self, option: &'static str, path: &'a Path) -> Self {
        self.outputs.push((option, path, Kind::File));
        self
    }

    /// An optional output file.
    pub fn maybe_output(self, option: &'static str, path: Option<&'a PathBuf>) -> Self {
        match path {
            Some(path) => self.output(option, path),
            None => self,
        }
    }

    /// An output directory: the command writes files into it, so no input may lie anywhere
    /// inside it.
    pub fn output_directory(mut self, option: &'static str, path: &'a Path) -> Self {
        self.outputs.push((option, path, Kind::Directory));
        self
    }

    /// Refuses outputs that are one of the inputs (or, for a directory, hold one), and
    /// outputs that are the same file as another output. Touches no file's contents.
    pub fn check(&self) -> Result<(), CliError> {
        let any_file = self.outputs.iter().any(|(_, _, kind)| *kind == Kind::File);
        // Each input directory's entries resolved once (an output file outside the directory
        // may still be one of them through a link).
        let inputs: Vec<(&str, &Path, Resolved, Entries)> = self
            .inputs
            .iter()
            .map(|(option, path)| {
                let resolved = Resolved::new(path);
                let entries = if any_file && resolved.directory {
                    entries(path)
                } else {
                    Vec::new()
                };
                (*option, path.as_ref(), resolved, entries)
            })
            .collect();
        let outputs: Vec<(&str, &Path, Kind, Resolved)> = self
            .outputs
            .iter()
            .map(|(option, path, kind)| (*option, *path, *kind, Resolved::new(path)))
            .collect();
        for (k, (output, out_path, kind, out)) in outputs.iter().enumerate() {
            for (input, in_path, resolved_input, entries) in &inputs {
                // (An output inside the directory is refused below, with its own message.)
                if *kind == Kind::File
                    && !out.path.starts_with(&resolved_input.path)
                    && let Some((entry, _)) = entries.iter().find(|(_, e)| e.same_file(out))
                {
                    return Err(CliError::input(format!(
                        "{output} {} is the same file as {} in {input} {}, a directory the \
                         command reads (a link to it, or the link's target): writing there \
                         would destroy that input; give another output path",
                        out_path.display(),
                        entry.display(),
                        in_path.display()
                    )));
                }
                match kind {
                    Kind::File if out.same_file(resolved_input) => {
                        return Err(CliError::input(format!(
                            "{output} {} is the same file as {input} {}: writing there would \
                             destroy the input; give another output path",
                            out_path.display(),
                            in_path.display()
                        )));
                    }
                    _ if resolved_input.directory && out.path.starts_with(&resolved_input.path) => {
                        return Err(CliError::input(format!(
                            "{output} {} lies inside {input} {}, a directory the command reads \
                             (a model set's directory reads every file in it as a channel): \
                             writing there could replace or add to its files; give a path \
                             outside it",
                            out_path.display(),
                            in_path.display()
                        )));
                    }
                    Kind::Directory if resolved_input.path.starts_with(&out.path) => {
                        return Err(CliError::input(format!(
                            "{output} {} holds the input {input} {}: the command writes its \
                             files there and could replace it; give another directory or \
                             move the input",
                            out_path.display(),
                            in_path.display()
                        )));
                    }
                    _ => {}
                }
            }
            for (other, other_path, other_kind, resolved_other) in &outputs[..k] {
                let clash = match (kind, other_kind) {
                    (Kind::File, Kind::File) => out.same_file(resolved_other),
                    (Kind::File, Kind::Directory) => out.path.starts_with(&resolved_other.path),
                    (Kind::Directory, Kind::File) => resolved_other.path.starts_with(&out.path),
                    (Kind::Directory, Kind::Directory) => {
                        out.path.starts_with(&resolved_other.path)
                            || resolved_other.path.starts_with(&out.path)
                    }
                };
                if clash {
                    return Err(CliError::input(format!(
                        "{other} and {output} name the same place ({} and {}): one result \
                         would overwrite the other; give two different paths",
                        other_path.display(),
                        out_path.display()
                    )));
                }
            }
        }
        Ok(())
    }
}

/// The most entries of an input directory [`entries`] looks at: more than a model set may
/// hold ([`hystcomp_io::bank::MAX_CHANNELS`]), which its reader refuses anyway.
const MAX_LISTED: usize = 1 << 17;

/// A directory's entries, each with its resolved path.
type Entries = Vec<(PathBuf, Resolved)>;

/// The entries of the directory `dir`, each resolved (a symbolic or hard link the directory
/// holds makes a file outside it one of its inputs); none when it cannot be listed.
fn entries(dir: &Path) -> Entries {
    let Ok(listing) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    listing
        .take(MAX_LISTED)
        .filter_map(Result::ok)
        .map(|entry| {
            let path = entry.path();
            let resolved = Resolved::new(&path);
            (path, resolved)
        })
        .collect()
}

/// A path as the file system resolves it.
#[derive(Debug)]
struct Resolved {
    /// Canonical when the file exists; else its nearest existing ancestor canonical, joined
    /// with the rest (with `.` and `..` resolved by name).
    path: PathBuf,
    /// Device and inode of an existing file (Unix), which also identify hard links.
    id: Option<(u64, u64)>,
    /// Whether the path is an existing directory (an input directory may hold no output).
    directory: bool,
}

impl Resolved {
    fn new(path: &Path) -> Self {
        Resolved {
            path: resolve(path),
            id: file_id(path),
            directory: path.is_dir(),
        }
    }

    fn same_file(&self, other: &Resolved) -> bool {
        self.path == other.path || (self.id.is_some() && self.id == other.id)
    }
}

/// Canonical `path`, or (when it does not exist) its nearest existing ancestor canonical with
/// the remaining components joined on.
fn resolve(path: &Path) -> PathBuf {
    if let Ok(canonical) = path.canonicalize() {
        return canonical;
    }
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let mut ancestor = absolute.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(canonical) = ancestor.canonicalize() {
            return rest.iter().rev().fold(canonical, |mut p, c| {
                push_component(&mut p, *c);
                p
            });
        }
        match (ancestor.parent(), ancestor.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                ancestor = parent;
            }
            _ => return absolute,
        }
    }
}

/// Appends one component, resolving `.` and `..` by name (the path does not exist, so there
/// is no link to follow).
fn push_component(path: &mut PathBuf, component: Component<'_>) {
    match component {
        Component::CurDir => {}
        Component::ParentDir => {
            path.pop();
        }
        other => path.push(other),
    }
}

#[cfg(unix)]
fn file_id(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn file_id(_path: &Path) -> Option<(u64, u64)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(path: &Path) {
        std::fs::write(path, "x").unwrap();
    }

    /// An output outside an input directory that one of the directory's entries links to
    /// (symbolically or by a hard link) is that input: refused, its contents untouched.
    #[cfg(unix)]
    #[test]
    fn an_output_linked_from_an_input_directory_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let models = dir.path().join("models");
        std::fs::create_dir(&models).unwrap();
        let target = dir.path().join("x.json");
        touch(&target);
        std::os::unix::fs::symlink(&target, models.join("x.json")).unwrap();
        let hard = dir.path().join("y.json");
        touch(&hard);
        std::fs::hard_link(&hard, models.join("y.json")).unwrap();
        for out in [&target, &hard] {
            let err = Files::new()
                .input("--model", &models)
                .output("--output", out)
                .check()
                .unwrap_err();
            assert!(err.to_string().contains("in --model"), "{err}");
            assert_eq!(std::fs::read_to_string(out).unwrap(), "x");
        }
        // A file beside them that no entry links to is a valid output.
        let other = dir.path().join("drive.csv");
        Files::new()
            .input("--model", &models)
            .output("--output", &other)
            .check()
            .unwrap();
    }

    /// A stage file's MPIM model file is an input of every command that reads the stage: an
    /// output there is refused (relative to the stage file's directory, as the stage reads it).
    #[test]
    fn a_stage_files_model_file_is_an_input() {
        let dir = tempfile::tempdir().unwrap();
        let stage = dir.path().join("stage.toml");
        std::fs::write(
            &stage,
            "[hysteresis]\nmodel = \"mpim\"\n[hysteresis.mpim]\nmodel_file = \"m.json\"\n",
        )
        .unwrap();
        let model = dir.path().join("m.json");
        touch(&model);
        let err = Files::new()
            .stage("--stage", Some(&stage))
            .output("--output", &model)
            .check()
            .unwrap_err();
        assert!(
            err.to_string().contains("hysteresis.mpim.model_file"),
            "{err}"
        );
        assert!(
            Files::new()
                .stage("--stage", Some(&stage))
                .output("--output", &stage)
                .check()
                .is_err()
        );
        Files::new()
            .stage("--stage", Some(&stage))
            .output("--output", &dir.path().join("out.csv"))
            .check()
            .unwrap();
        // No stage, or one that cannot be read, names nothing more.
        Files::new()
            .stage("--stage", None)
            .output("--output", &model)
            .check()
            .unwrap();
        let broken = dir.path().join("broken.toml");
        std::fs::write(&broken, "not = [toml").unwrap();
        Files::new()
            .stage("--stage", Some(&broken))
            .output("--output", &model)
            .check()
            .unwrap();
    }

    #[test]
    fn output_naming_an_input_is_refused_by_every_spelling() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.csv");
        touch(&input);
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let spellings = [
            input.clone(),
            dir.path().join("sub/../in.csv"),
            dir.path().join("./in.csv"),
        ];
        for out in &spellings {
            let err = Files::new()
                .input("--data", &input)
                .output("--output", out)
                .check()
                .expect_err("refused");
            assert!(err.to_string().contains("same file as --data"), "{err}");
        }
        #[cfg(unix)]
        {
            let link = dir.path().join("link.csv");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            let hard = dir.path().join("hard.csv");
            std::fs::hard_link(&input, &hard).unwrap();
            let linked_dir = dir.path().join("linked");
            std::os::unix::fs::symlink(dir.path(), &linked_dir).unwrap();
            for out in [link, hard, linked_dir.join("in.csv")] {
                assert!(
                    Files::new()
                        .input("--data", &input)
                        .output("--output", &out)
                        .check()
                        .is_err(),
                    "{} accepted",
                    out.display()
                );
            }
        }
    }

    #[test]
    fn new_outputs_and_other_files_are_accepted() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.csv");
        touch(&input);
        for out in [
            dir.path().join("out.csv"),
            dir.path().join("missing/dir/in.csv"),
            dir.path().join("in.csv.bak"),
        ] {
            Files::new()
                .input("--data", &input)
                .output("--output", &out)
                .check()
                .unwrap();
        }
    }

    #[test]
    fn directories_may_not_hold_inputs_nor_input_directories_outputs_and_outputs_may_not_clash() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("report/stage.toml");
        std::fs::create_dir(dir.path().join("report")).unwrap();
        touch(&input);
        let err = Files::new()
            .input("--stage", &input)
            .output_directory("--out", &dir.path().join("report"))
            .check()
            .unwrap_err();
        assert!(err.to_string().contains("holds the input --stage"), "{err}");
        Files::new()
            .input("--stage", &input)
            .output_directory("--out", &dir.path().join("report2"))
            .check()
            .unwrap();
        // An input directory (a model set's) holds no output, new file or not, by any spelling.
        let set = dir.path().join("set");
        std::fs::create_dir(&set).unwrap();
        touch(&set.join("x.json"));
        for out in [
            set.join("x.json"),
            set.join("new.json"),
            set.join("sub/drive.csv"),
            dir.path().join("report/../set/y.csv"),
        ] {
            let err = Files::new()
                .input("--model", &set)
                .output("--output", &out)
                .check()
                .expect_err("refused");
            assert!(err.to_string().contains("lies inside --model"), "{err}");
            let err = Files::new()
                .input("--model", &set)
                .output_directory("--out", &out)
                .check()
                .expect_err("refused");
            assert!(err.to_string().contains("lies inside --model"), "{err}");
        }
        Files::new()
            .input("--model", &set)
            .output("--output", &dir.path().join("set.csv"))
            .check()
            .unwrap();
        let a = dir.path().join("a.json");
        let err = Files::new()
            .output("--save-plant", &a)
            .output("--save-inverse", &dir.path().join("./a.json"))
            .check()
            .unwrap_err();
        assert!(err.to_string().contains("same place"), "{err}");
    }
}
