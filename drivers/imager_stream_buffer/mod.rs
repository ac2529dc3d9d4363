//! `vrpn_Imager_Stream_Buffer NAME UPSTREAM`: an imager served as `NAME` whose frames come
//! from the imager `UPSTREAM` (`Name@host[:port]`, or `*Name` on this server), relayed in the
//! server's own loop by [`ImagerRelay`]. C++ runs a
//! second thread for this; here the upstream connection waits in the server's reactor.
//!
//! C++'s class is also an auxiliary logger that logs the upstream connection on request;
//! that part is not served here (a client's logging request gets no answer).

use crate::config::{ConfigError, ConfigLine, DeviceRef};
use crate::devices::imager::ImagerRelay;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Imager_Stream_Buffer"],
    parse,
    hints: &[],
};

/// `vrpn_Imager_Stream_Buffer NAME UPSTREAM`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StreamBuffer {
    /// The name served.
    pub name: String,
    /// The imager relayed.
    pub upstream: DeviceRef,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, imager server to buffer (Name@host)")?;
    let upstream = line
        .device_ref(1, "imager server to buffer", false)?
        .expect("NULL is refused");
    Ok(Box::new(StreamBuffer {
        name: line.name(0)?,
        upstream,
    }))
}

impl DeviceSpec for StreamBuffer {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Imager])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(ImagerRelay::new(
            &self.name,
            cx.conn(),
            self.upstream.name(),
        )?)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::config::{parse_one, parse_str};

    #[test]
    fn parses_and_refuses() {
        let spec: StreamBuffer =
            parse_one("vrpn_Imager_Stream_Buffer Relay0 TestImage@localhost:3884\n");
        assert_eq!(spec.name, "Relay0");
        assert_eq!(spec.upstream.name(), "TestImage@localhost:3884");
        assert_eq!(spec.served(), Served::all("Relay0", &[Interface::Imager]));
        for bad in [
            "vrpn_Imager_Stream_Buffer Relay0\n",
            "vrpn_Imager_Stream_Buffer Relay0 NULL\n",
            "vrpn_Imager_Stream_Buffer Relay0 TestImage\n",
        ] {
            let e = parse_str(bad, "test.cfg").unwrap_err();
            assert!(
                e.to_string()
                    .starts_with("test.cfg:1: vrpn_Imager_Stream_Buffer"),
                "{e}"
            );
        }
    }
}
