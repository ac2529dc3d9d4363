//! Placeholder so the package builds until the real `vrpn_ping` program lands.

fn main() {
    eprintln!("vrpn_ping: not implemented yet");
    std::process::exit(1);
}
