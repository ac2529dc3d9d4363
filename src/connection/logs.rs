//! Logging a connection's messages to `.vrpn` files (C++ `-li`/`-lo`).

use super::Connection;
use crate::error::Error;

impl Connection {
    /// Logs every message this side receives to a new file at `path` (C++ format; an
    /// existing file is never overwritten). A client logs into one file across reconnects; a
    /// server opens one file per client, `in.vrpn` → `in-1.vrpn`, `in-2.vrpn`, … (`-li`).
    pub fn log_incoming(&self, path: &str) -> Result<(), Error> {
        let mut core = self.inner.core.borrow_mut();
        if core.shell.server_port().is_some() {
            let template = path.to_string();
            core.session.set_incoming_log(
                None,
                Some(Box::new(move |n| {
                    crate::log::open_sink(&compound_log_name(&template, n))
                })),
            );
        } else {
            let sink = crate::log::open_sink(path).map_err(Error::from_log)?;
            core.session.set_incoming_log(Some(sink), None);
        }
        Ok(())
    }

    /// Logs every message this side sends (descriptions included) to a new file at `path`
    /// (`-lo`). A server logs from now on, clients connected or not.
    pub fn log_outgoing(&self, path: &str) -> Result<(), Error> {
        let sink = crate::log::open_sink(path).map_err(Error::from_log)?;
        self.inner.core.borrow_mut().session.set_outgoing_log(sink);
        Ok(())
    }

    /// Writes all buffered log data now (`vrpn_server -flush` calls it every pass). Otherwise
    /// each `mainloop()` writes a bounded amount and the rest goes out when the connection
    /// closes.
    pub fn flush_logs(&self) -> Result<(), Error> {
        self.inner
            .core
            .borrow_mut()
            .session
            .flush_logs_all()
            .map_err(Error::from_log)
    }

    /// Ends logging: writes the closing DISCONNECT entry of an outgoing log and flushes.
    pub fn close_logs(&self) -> Result<(), Error> {
        let now = self.now();
        self.inner
            .core
            .borrow_mut()
            .session
            .close_logs(now)
            .map_err(Error::from_log)
    }
}

/// `in.vrpn` → `in-3.vrpn`: `-N` before the last `.` (appended when there is none), as C++.
pub(crate) fn compound_log_name(template: &str, n: u32) -> String {
    match template.rfind('.') {
        Some(i) => format!("{}-{n}{}", &template[..i], &template[i..]),
        None => format!("{template}-{n}"),
    }
}
