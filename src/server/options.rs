//! The `vrpn_server` command line, with the C++ single-dash spellings and meanings.

use std::net::Ipv4Addr;
use std::time::Duration;

/// How the server loop waits between passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SleepPolicy {
    /// Block in the poll until a socket is ready or a device deadline comes, then keep polling
    /// without blocking for `busy_window` after incoming traffic. Latency of a spinning server,
    /// about 0% CPU when idle. The default.
    EventDriven {
        /// How long to keep spinning after incoming data.
        busy_window: Duration,
        /// Longest single block (`-millisleep N` with N > 0 caps it at N ms).
        max_block: Duration,
    },
    /// Never block (`-millisleep 0` or `-millisleep -1`): lowest latency, one core at 100%.
    Spin,
}

/// Parsed `vrpn_server` options.
#[derive(Clone, Debug, PartialEq)]
pub struct ServerOptions {
    /// Configuration file (`-f`, default `vrpn.cfg`).
    pub config: String,
    /// Warn and skip bad config entries instead of aborting (`-warn`).
    pub warn_only: bool,
    /// Verbose (`-v`): print what is opened, show NORMAL texts too.
    pub verbose: bool,
    /// Quiet (`-quiet`): no start-up line, only warnings and errors.
    pub quiet: bool,
    /// Quit when the last client leaves (`-q`).
    pub quit_after_last: bool,
    /// Loop wait policy (`-millisleep`).
    pub sleep: SleepPolicy,
    /// Listen on one interface only (`-NIC ADDR`).
    pub nic: Option<Ipv4Addr>,
    /// Log incoming messages (`-li FILE`).
    pub log_in: Option<String>,
    /// Log outgoing messages (`-lo FILE`).
    pub log_out: Option<String>,
    /// Flush logs every pass (`-flush`).
    pub flush_logs: bool,
    /// Folder for the logs clients ask for (`-logdir DIR`): remote log names sent at connect
    /// time, and auxiliary loggers whose configuration line names no folder. Without it such
    /// requests are refused.
    pub log_dir: Option<String>,
    /// Ports clients may ask this server to forward devices on (`-forwardports LOW-HIGH`,
    /// C++ `vrpn_Forwarder_Server`); `None` refuses such requests.
    pub forward_ports: Option<std::ops::RangeInclusive<u16>>,
    /// Listen port (default 3883; 0 picks a free one and prints it).
    pub port: u16,
    /// Call clients back at the address their connection request names rather than the
    /// address it came from (`-callbacknamed`; multi-homed clients that ask from one interface
    /// and listen on another). Off by default: see `Limits::callback_to_named_address`.
    pub callback_to_named_address: bool,
    /// Seconds this process's wall clock is moved ahead (`-clockshift S`): makes the server
    /// stamp its messages as a host whose clock is off would, to see clock synchronisation
    /// at work. See [`crate::time::shift_wall_clock`].
    pub clock_shift: Option<f64>,
    /// Where USB HID and input devices are found (`-devroot DIR`: `DIR/sys` and `DIR/dev`,
    /// hot-plug on `DIR/uevent`), for device simulators; the system's `/sys` and `/dev`
    /// otherwise.
    pub device_root: Option<String>,
    /// List the HID and input devices plugged in, with the lines that would serve them, and
    /// exit (`--list-devices`).
    pub list_devices: bool,
}

impl Default for ServerOptions {
    fn default() -> Self {
        ServerOptions {
            config: "vrpn.cfg".into(),
            warn_only: false,
            verbose: false,
            quiet: false,
            quit_after_last: false,
            sleep: SleepPolicy::EventDriven {
                busy_window: Duration::from_millis(2),
                max_block: Duration::from_millis(100),
            },
            nic: None,
            log_in: None,
            log_out: None,
            flush_logs: false,
            log_dir: None,
            forward_ports: None,
            port: crate::wire::DEFAULT_PORT,
            callback_to_named_address: false,
            clock_shift: None,
            device_root: None,
            list_devices: false,
        }
    }
}

/// What a `vrpn_server` command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum ServerCommand {
    /// Serve with these options.
    Serve(ServerOptions),
    /// Print [`USAGE`] (`-h`, `-help`, `--help`).
    Help,
    /// Print the version (`--version`).
    Version,
}

/// Usage text.
pub const USAGE: &str = "usage: vrpn_server [-f FILE] [-warn] [-v] [-quiet] [-q] [-millisleep N] \
[-NIC ADDR] [-li FILE] [-lo FILE] [-flush] [-logdir DIR] [-forwardports LOW-HIGH]
       [-callbacknamed] [-clockshift S] [-devroot DIR] [PORT]
       vrpn_server --list-devices [-devroot DIR]
       vrpn_server -h | --help | --version
  -f FILE         configuration file (default vrpn.cfg)
  -warn           skip bad configuration entries with a warning instead of stopping
  -v              verbose: print each device opened and show every text message
  -quiet          print only warnings and errors (no start-up line)
  -q              quit when the last client disconnects
  -millisleep N   N > 0: block at most N ms per pass; 0 or -1: spin (100% CPU);
                  default: sleep until a socket or device needs service
  -NIC ADDR       listen only on the interface with this IPv4 address
  -li FILE        log incoming messages to FILE
  -lo FILE        log outgoing messages to FILE
  -flush          flush logs on every pass
  -logdir DIR     write the logs clients ask for (remote log names, auxiliary loggers)
                  inside DIR, under plain file names that do not exist yet; without it
                  clients' log requests are refused
  -forwardports LOW-HIGH
                  let clients (C++ forwarderClient, vrpn::forward::ForwarderController)
                  open ports in LOW-HIGH and forward this server's devices there;
                  without it such requests are refused
  -callbacknamed  call UDP-path clients back at the (numeric) address their request
                  names, not the address it came from (multi-homed clients only)
  -clockshift S   stamp messages as if this host's clock were S seconds ahead (to
                  watch clients synchronise their clocks to it; not for production)
  -devroot DIR    look for USB HID and input devices under DIR/sys and DIR/dev (device
                  simulators; hot-plug events on the datagram socket DIR/uevent)
  --list-devices  list the HID and input devices plugged in, each with the vrpn.cfg
                  lines that would serve it, and exit
  PORT            UDP and TCP port to listen on (default 3883; 0 picks a free one)
  -h, --help      print this help
  --version       print the version";

/// A command-line problem; displays as a one-line message for the user.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum OptionError {
    /// An option that takes a value came last.
    MissingValue(&'static str),
    /// An option's value is not what it must be: the option, the value, what was expected.
    BadValue(&'static str, String, &'static str),
    /// An option this program does not have.
    Unknown(String),
    /// A second port, or any other word that is not an option.
    Unexpected(String),
}

impl std::fmt::Display for OptionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OptionError::MissingValue(flag) => {
                write!(f, "{flag} needs a value (see vrpn_server -h)")
            }
            OptionError::BadValue(flag, v, expected) => {
                write!(f, "{flag} {v:?}: expected {expected}")
            }
            OptionError::Unknown(s) => write!(f, "unknown option {s} (see vrpn_server -h)"),
            OptionError::Unexpected(s) => {
                write!(f, "unexpected argument {s:?} (see vrpn_server -h)")
            }
        }
    }
}

impl std::error::Error for OptionError {}

/// Parses arguments (without the program name).
pub fn parse_args<I: IntoIterator<Item = String>>(args: I) -> Result<ServerCommand, OptionError> {
    let mut o = ServerOptions::default();
    let mut it = args.into_iter();
    let mut port_seen = false;
    while let Some(a) = it.next() {
        let mut value = |flag: &'static str| it.next().ok_or(OptionError::MissingValue(flag));
        match a.as_str() {
            "-f" => o.config = value("-f")?,
            "-warn" => o.warn_only = true,
            "-v" => o.verbose = true,
            "-quiet" => o.quiet = true,
            "-logdir" => o.log_dir = Some(value("-logdir")?),
            "-forwardports" => {
                let v = value("-forwardports")?;
                o.forward_ports = Some(parse_port_range(&v).ok_or_else(|| {
                    OptionError::BadValue("-forwardports", v.clone(), "a port or a range LOW-HIGH")
                })?);
            }
            "-q" => o.quit_after_last = true,
            "-flush" => o.flush_logs = true,
            "-callbacknamed" => o.callback_to_named_address = true,
            "-clockshift" => {
                let v = value("-clockshift")?;
                let s: f64 = v
                    .parse()
                    .ok()
                    .filter(|s: &f64| s.is_finite())
                    .ok_or_else(|| {
                        OptionError::BadValue("-clockshift", v.clone(), "a number of seconds")
                    })?;
                o.clock_shift = Some(s);
            }
            "-devroot" => o.device_root = Some(value("-devroot")?),
            "--list-devices" => o.list_devices = true,
            "-li" => o.log_in = Some(value("-li")?),
            "-lo" => o.log_out = Some(value("-lo")?),
            "-NIC" => {
                let v = value("-NIC")?;
                o.nic = Some(v.parse().map_err(|_| {
                    OptionError::BadValue(
                        "-NIC",
                        v.clone(),
                        "the IPv4 address of a local interface",
                    )
                })?);
            }
            "-millisleep" => {
                let v = value("-millisleep")?;
                let n: i64 = v.parse().map_err(|_| {
                    OptionError::BadValue("-millisleep", v.clone(), "a whole number")
                })?;
                o.sleep = if n <= 0 {
                    SleepPolicy::Spin
                } else {
                    SleepPolicy::EventDriven {
                        busy_window: Duration::from_millis(2),
                        max_block: Duration::from_millis(n as u64),
                    }
                };
            }
            "-h" | "--help" | "-help" => return Ok(ServerCommand::Help),
            "--version" => return Ok(ServerCommand::Version),
            s if s.starts_with('-') => return Err(OptionError::Unknown(s.to_owned())),
            s => {
                if port_seen {
                    return Err(OptionError::Unexpected(s.to_owned()));
                }
                port_seen = true;
                o.port = s.parse().map_err(|_| {
                    OptionError::BadValue("port", s.to_owned(), "a number from 0 to 65535")
                })?;
            }
        }
    }
    Ok(ServerCommand::Serve(o))
}

/// `4500` or `4500-4510`.
fn parse_port_range(text: &str) -> Option<std::ops::RangeInclusive<u16>> {
    let (low, high) = text.split_once('-').unwrap_or((text, text));
    let (low, high): (u16, u16) = (low.trim().parse().ok()?, high.trim().parse().ok()?);
    (low >= 1 && low <= high).then_some(low..=high)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_string).collect()
    }

    /// The options of a command line that must parse to `Serve`.
    fn serve(s: &str) -> ServerOptions {
        match parse_args(args(s)) {
            Ok(ServerCommand::Serve(o)) => o,
            other => panic!("{s}: {other:?}"),
        }
    }

    #[test]
    fn cpp_options() {
        let o = serve("-f x.cfg -warn -v -q -millisleep 5 -NIC 127.0.0.1 4000 -li in.vrpn -lo out.vrpn -flush");
        assert_eq!(o.config, "x.cfg");
        assert!(o.warn_only && o.verbose && o.quit_after_last);
        assert_eq!(o.nic, Some(Ipv4Addr::LOCALHOST));
        assert_eq!(o.port, 4000);
        assert_eq!(o.log_in.as_deref(), Some("in.vrpn"));
        assert_eq!(o.log_out.as_deref(), Some("out.vrpn"));
        assert!(o.flush_logs);
        assert!(!o.callback_to_named_address);
        assert!(serve("-callbacknamed").callback_to_named_address);
        assert!(serve("-quiet").quiet);
        assert_eq!(serve("-logdir logs").log_dir.as_deref(), Some("logs"));
        assert_eq!(
            serve("-forwardports 4500-4510").forward_ports,
            Some(4500..=4510)
        );
        assert_eq!(serve("-forwardports 4500").forward_ports, Some(4500..=4500));
        for bad in ["-forwardports 10-5", "-forwardports 0", "-forwardports x"] {
            assert!(parse_args(args(bad)).is_err(), "{bad}");
        }
        assert_eq!(serve("-clockshift -3600.5").clock_shift, Some(-3600.5));
        assert!(parse_args(args("-clockshift soon")).is_err());
        assert!(
            matches!(o.sleep, SleepPolicy::EventDriven { max_block, .. } if max_block == Duration::from_millis(5))
        );
        assert_eq!(serve("-millisleep -1").sleep, SleepPolicy::Spin);
        assert_eq!(serve(""), ServerOptions::default());
        for help in ["-h", "-help", "--help", "-v -h"] {
            assert_eq!(parse_args(args(help)), Ok(ServerCommand::Help));
        }
        assert_eq!(parse_args(args("--version")), Ok(ServerCommand::Version));
    }

    #[test]
    fn clear_errors() {
        assert!(parse_args(args("-NIC eth0"))
            .unwrap_err()
            .to_string()
            .contains("IPv4"));
        assert!(parse_args(args("-f"))
            .unwrap_err()
            .to_string()
            .contains("needs a value"));
        assert!(parse_args(args("abc"))
            .unwrap_err()
            .to_string()
            .contains("port"));
        let e = parse_args(args("-bogus")).unwrap_err().to_string();
        assert_eq!(e, "unknown option -bogus (see vrpn_server -h)");
        assert!(!e.contains('\n'));
    }
}
