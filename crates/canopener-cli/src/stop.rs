//! Ctrl-C and SIGTERM handling: long-running commands poll a flag and finish cleanly (flush logs, print a
//! summary) instead of dying mid-write.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::CliError;

/// Set once when the user asks us to stop.
#[derive(Debug, Clone)]
pub(crate) struct StopFlag(Arc<AtomicBool>);

impl StopFlag {
    /// Installs the process-wide handler. Only the first call installs it; later calls share the flag.
    pub(crate) fn install() -> Result<StopFlag, CliError> {
        static FLAG: std::sync::OnceLock<Arc<AtomicBool>> = std::sync::OnceLock::new();
        let mut install_error = None;
        let flag = FLAG.get_or_init(|| {
            let flag = Arc::new(AtomicBool::new(false));
            let handler_flag = Arc::clone(&flag);
            if let Err(err) = ctrlc::set_handler(move || handler_flag.store(true, Ordering::SeqCst)) {
                install_error = Some(err);
            }
            flag
        });
        if let Some(err) = install_error {
            return Err(CliError::Internal(anyhow::anyhow!(
                "cannot install the Ctrl-C handler: {err}"
            )));
        }
        Ok(StopFlag(Arc::clone(flag)))
    }

    pub(crate) fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}
