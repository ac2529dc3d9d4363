//! Placeholder so the package builds until the real `vrpn_print_devices` program lands.

fn main() {
    eprintln!("vrpn_print_devices: not implemented yet");
    std::process::exit(1);
}
