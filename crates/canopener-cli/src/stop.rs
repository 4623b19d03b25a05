//! Ctrl-C and SIGTERM handling: long-running commands poll a flag and finish cleanly (flush logs, print a
//! summary) instead of dying mid-write.

use canopener_link::cancel::Cancel;

use crate::error::CliError;

/// Set once when the user asks us to stop: the process-wide [`Cancel`] token the signal handler cancels.
#[derive(Debug, Clone)]
pub(crate) struct StopFlag(Cancel);

impl StopFlag {
    /// Installs the process-wide handler. Only the first call installs it; later calls share the flag.
    pub(crate) fn install() -> Result<StopFlag, CliError> {
        static FLAG: std::sync::OnceLock<Cancel> = std::sync::OnceLock::new();
        let mut install_error = None;
        let flag = FLAG.get_or_init(|| {
            let flag = Cancel::new();
            let handler_flag = flag.clone();
            if let Err(err) = ctrlc::set_handler(move || handler_flag.cancel()) {
                install_error = Some(err);
            }
            flag
        });
        if let Some(err) = install_error {
            return Err(CliError::Internal(anyhow::anyhow!(
                "cannot install the Ctrl-C handler: {err}"
            )));
        }
        Ok(StopFlag(flag.clone()))
    }

    /// The token to hand to the runtime's loops.
    pub(crate) fn token(&self) -> Cancel {
        self.0.clone()
    }
}
