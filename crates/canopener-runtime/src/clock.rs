//! The calendar time, for what a report states about when it was made (front ends may not read
//! clocks themselves).

use std::time::SystemTime;

/// The system's calendar time now.
pub fn wall_time() -> SystemTime {
    SystemTime::now()
}
