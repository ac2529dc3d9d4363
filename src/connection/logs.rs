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

    /// Client: asks the server to log this connection (`incoming`: what the server receives
    /// from us, `outgoing`: what it sends us; "" for none), as C++'s
    /// `vrpn_get_connection_by_name` remote log names do. The request goes out with the next
    /// greeting, once: call it before the connection is first made (right after opening it).
    ///
    /// The names are the server's to interpret. A C++ server writes them where it runs; a
    /// server of this crate takes plain file names, written inside a folder its operator named
    /// (`vrpn_server -logdir DIR`), and closes the connection when it cannot honour them
    /// (the name exists, it is a path), which is how VRPN tells a client that remote logging
    /// failed. Without such a folder it refuses with a notice and keeps serving.
    pub fn request_remote_logging(&self, incoming: &str, outgoing: &str) -> Result<(), Error> {
        let mut core = self.inner.core.borrow_mut();
        if !core.session.is_client() {
            return Err(Error::Unsupported(
                "remote logging is requested by a client of a network server",
            ));
        }
        let request = crate::proto::RemoteLogRequest {
            incoming: incoming.to_string(),
            outgoing: outgoing.to_string(),
        };
        core.session.set_remote_log_request(Some(request));
        Ok(())
    }

    /// Server: writes the logs clients ask for (remote logging) into `folder`, under the names
    /// they give when these are plain file names that do not exist yet; other requests close
    /// the asking client's connection. `None` (the default) refuses every request with a
    /// notice and keeps serving the client.
    pub fn set_remote_log_folder(&self, folder: Option<crate::log::LogFolder>) {
        self.inner
            .core
            .borrow_mut()
            .session
            .set_remote_log_folder(folder);
    }

    /// Logs what a client receives into a file already created (a folder's).
    pub(crate) fn log_incoming_file(&self, file: std::fs::File, path: &std::path::Path) {
        let sink = crate::log::sink_from_file(file, path);
        let mut core = self.inner.core.borrow_mut();
        core.session.set_incoming_log(Some(sink), None);
    }

    /// Logs what this side sends into a file already created (a folder's).
    pub(crate) fn log_outgoing_file(&self, file: std::fs::File, path: &std::path::Path) {
        let sink = crate::log::sink_from_file(file, path);
        self.inner.core.borrow_mut().session.set_outgoing_log(sink);
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
