//! What the `ppmc fuzz` subcommands that read fuzz inputs share: the
//! input's kind, the model it is judged on, the inputs under a folder.

use crate::{usage, CliError};
use clap::Args;
use ppmc::emu::ModelConfig;
use ppmc::fuzzing::finding::{self, InputKind};
use std::path::{Path, PathBuf};

/// The fuzz targets whose inputs are bus programs, as `--kind` names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Kind {
    /// A `bus_bytes` input: ops separated by `FUZZ`.
    BusBytes,
    /// A `typed_actions` input: typed actions (derive `Arbitrary`).
    TypedActions,
}

impl From<Kind> for InputKind {
    fn from(k: Kind) -> InputKind {
        match k {
            Kind::BusBytes => InputKind::BusBytes,
            Kind::TypedActions => InputKind::TypedActions,
        }
    }
}

#[derive(Debug, Args)]
pub(crate) struct ModelArgs {
    /// Which fuzz target the inputs are for.
    #[arg(long, value_enum, default_value = "bus-bytes")]
    pub(crate) kind: Kind,
    /// Judge on an emulator with this board fault (`ppmc fault-matrix
    /// --list`); repeat to combine. Default: the clean emulator.
    #[arg(long = "chip-fault", value_name = "FAULT")]
    chip_faults: Vec<String>,
}

impl ModelArgs {
    pub(crate) fn model(&self) -> Result<ModelConfig, CliError> {
        let mut cfg = ModelConfig::default();
        ppmc::faults::apply_all(&self.chip_faults, &mut cfg)
            .map_err(|e| usage(format!("--chip-fault: {e}")))?;
        Ok(cfg)
    }
}

/// The inputs under `paths` (files, or the files of directories, sorted),
/// as bus ops.
pub(crate) fn load_inputs(
    paths: &[PathBuf],
    kind: InputKind,
    cfg: &ModelConfig,
) -> Result<Vec<(String, Vec<ppmc::bus_program::BusOp>)>, CliError> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let rd = std::fs::read_dir(p)
                .map_err(|e| usage(format!("cannot read {}: {e}", p.display())))?;
            let mut v: Vec<PathBuf> = rd
                .filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|f| f.is_file())
                .collect();
            v.sort();
            files.extend(v);
        } else {
            files.push(p.clone());
        }
    }
    files
        .into_iter()
        .map(|f| {
            let data = ppmc_files::read(&f, ppmc_files::MAX_INPUT_BYTES)?;
            Ok((f.display().to_string(), finding::ops_of(&data, kind, cfg)))
        })
        .collect()
}

#[derive(Debug, Args)]
pub(crate) struct InputArgs {
    /// The input file.
    pub(crate) file: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
}

impl InputArgs {
    /// The model, the input's bytes and its bus ops.
    pub(crate) fn load(&self) -> Result<(ModelConfig, Vec<ppmc::bus_program::BusOp>), CliError> {
        let cfg = self.model.model()?;
        let data = ppmc_files::read(&self.file, ppmc_files::MAX_INPUT_BYTES)?;
        let ops = finding::ops_of(&data, self.model.kind.into(), &cfg);
        Ok((cfg, ops))
    }
}

pub(crate) fn with_suffix(p: &Path, suffix: &str) -> PathBuf {
    let mut s = p.as_os_str().to_owned();
    s.push(".");
    s.push(suffix);
    PathBuf::from(s)
}

/// The files of `dir`, sorted by name, as bytes.
pub(crate) fn read_folder(dir: &Path) -> Result<Vec<Vec<u8>>, CliError> {
    let rd =
        std::fs::read_dir(dir).map_err(|e| usage(format!("cannot read {}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| Ok(ppmc_files::read(f, 1 << 20)?))
        .collect()
}
