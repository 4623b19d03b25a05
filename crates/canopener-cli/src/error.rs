//! The CLI's error type and its mapping to the documented exit codes (see `cli::EXIT_CODES_HELP`).

use std::io;
use std::path::Path;

use canopener_transport::TransportError;

/// Exit codes, documented in `canopener --help` and the README.
pub(crate) mod exit_code {
    pub(crate) const SUCCESS: u8 = 0;
    pub(crate) const INTERNAL: u8 = 1;
    pub(crate) const USAGE: u8 = 2;
    pub(crate) const INVALID_INPUT: u8 = 3;
    pub(crate) const BUS: u8 = 4;
    pub(crate) const OUTPUT: u8 = 5;
    pub(crate) const CHECK_FAILED: u8 = 6;
    pub(crate) const DEVICE: u8 = 7;
    /// Ctrl-C or SIGTERM ended a command that was talking to a device (a transfer in progress was
    /// aborted on the bus); the shell convention 128 + SIGINT.
    pub(crate) const INTERRUPTED: u8 = 130;
}

/// Everything a command can fail with, grouped by what the user has to do about it.
#[derive(Debug, thiserror::Error)]
pub(crate) enum CliError {
    /// The arguments make no sense together; clap catches most of these before we run.
    #[error("{0}")]
    Usage(String),
    /// A file, frame or value given by the user could not be read.
    #[error("{0}")]
    InvalidInput(String),
    /// The bus could not be opened or failed while in use.
    #[error(transparent)]
    Bus(#[from] TransportError),
    /// A result could not be written.
    #[error("{context}: {source}")]
    Output {
        /// What we were writing, with the path.
        context: String,
        /// The operating system's reason.
        source: io::Error,
    },
    /// The command ran to the end and found a problem it was asked to check for.
    #[error("{0}")]
    CheckFailed(String),
    /// A device refused a request (SDO abort, LSS error code) or did not answer in time; the message
    /// names the node and object and decodes the abort code.
    #[error("{0}")]
    Device(String),
    /// A bug or an environment problem we did not anticipate.
    #[error(transparent)]
    Internal(#[from] anyhow::Error),
    /// An `eds` command could not read, accept or write a file (exit 2, as diff(1) does for trouble).
    #[error("{0}")]
    EdsTrouble(String),
    /// The command has already reported its result and ends with this exit code (e.g. `eds diff` → 1).
    #[error("")]
    Exit(u8),
}

impl CliError {
    pub(crate) fn exit_code(&self) -> u8 {
        match self {
            CliError::Usage(_) => exit_code::USAGE,
            CliError::InvalidInput(_) => exit_code::INVALID_INPUT,
            // A missing or malformed --bus is the user's argument, not the bus failing.
            CliError::Bus(
                TransportError::Spec(_)
                | TransportError::NoBusGiven
                | TransportError::EnvSpec(_)
                | TransportError::EnvNotUnicode,
            ) => exit_code::USAGE,
            CliError::Bus(_) => exit_code::BUS,
            CliError::Output { .. } => exit_code::OUTPUT,
            CliError::CheckFailed(_) => exit_code::CHECK_FAILED,
            CliError::Device(_) => exit_code::DEVICE,
            CliError::Internal(_) => exit_code::INTERNAL,
            CliError::EdsTrouble(_) => exit_code::USAGE,
            CliError::Exit(code) => *code,
        }
    }

    pub(crate) fn output(context: impl Into<String>, source: io::Error) -> CliError {
        CliError::Output {
            context: context.into(),
            source,
        }
    }

    pub(crate) fn read_file(path: &Path, source: io::Error) -> CliError {
        CliError::InvalidInput(format!("cannot read {}: {source}", path.display()))
    }

    /// Whether this error only means that whoever reads our stdout went away (`| head`).
    pub(crate) fn is_broken_pipe(&self) -> bool {
        matches!(self, CliError::Output { source, .. } if source.kind() == io::ErrorKind::BrokenPipe)
    }
}

/// A result file that could not be written: `eds` commands report it as trouble (exit 2, as diff(1) does);
/// commands that write what a device gave map it to an output error themselves.
impl From<canopener_files::WriteError> for CliError {
    fn from(err: canopener_files::WriteError) -> CliError {
        CliError::EdsTrouble(err.to_string())
    }
}

/// A result file or directory that could not be written, for the commands outside `eds`: an output error
/// (exit 5) naming what and where.
pub(crate) fn write_failed(err: canopener_files::WriteError) -> CliError {
    CliError::output(
        format!("cannot {} {}", err.action, err.path.display()),
        err.source,
    )
}

/// A failing bus is a bus error (exit 4); the simulated bus refusing a frame is a bug of ours.
impl From<canopener_link::link::LinkError> for CliError {
    fn from(err: canopener_link::link::LinkError) -> CliError {
        match err {
            canopener_link::link::LinkError::Transport(err) => CliError::Bus(err),
            other => CliError::Internal(anyhow::Error::new(other)),
        }
    }
}

/// A candump log that cannot be read is the user's input failing (exit 3), whichever command reads it.
impl From<canopener_runtime::candump_file::ReadLogError> for CliError {
    fn from(err: canopener_runtime::candump_file::ReadLogError) -> CliError {
        CliError::read_file(&err.path, err.source)
    }
}

/// A device description that cannot be read or loaded is trouble (exit 2, as diff(1) does), for every
/// command that takes one.
impl From<canopener_runtime::description::ReadError> for CliError {
    fn from(err: canopener_runtime::description::ReadError) -> CliError {
        CliError::EdsTrouble(err.to_string())
    }
}

pub(crate) type CliResult<T = ()> = Result<T, CliError>;

/// Wraps a write to stdout so that a closed pipe ends the command quietly.
pub(crate) fn stdout_error(source: io::Error) -> CliError {
    CliError::output("writing to stdout", source)
}

/// Simulated devices that cannot start: a file or state file the user gave is invalid input (exit 3),
/// node-IDs that do not fit together are a usage error (exit 2), a state directory that cannot be
/// created an output error (exit 5), a failing bus a bus error (exit 4).
impl From<canopener_sim::error::SimError> for CliError {
    fn from(err: canopener_sim::error::SimError) -> CliError {
        use canopener_sim::error::SimError;
        use canopener_sim::state_store::StateStoreError;
        match err {
            SimError::NodeIdAbove127 { .. } => CliError::Usage(format!("{err}; start --node-id lower")),
            SimError::InvalidNodeId { .. } | SimError::NodeIdClash { .. } => CliError::Usage(err.to_string()),
            SimError::StateStore(StateStoreError::CreateDir { dir, source }) => {
                CliError::output(format!("creating the state directory {}", dir.display()), source)
            }
            SimError::Bus(err) => CliError::Bus(err),
            SimError::Link(err) => err.into(),
            SimError::Read { .. }
            | SimError::NoObjects { .. }
            | SimError::Build { .. }
            | SimError::Serial { .. }
            | SimError::StateStore(_) => CliError::InvalidInput(err.to_string()),
        }
    }
}
