//! Placeholder so the package builds until the real `vrpn_server` program lands.

fn main() {
    eprintln!("vrpn_server: not implemented yet");
    std::process::exit(1);
}
