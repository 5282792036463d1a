//! Prints the instruction-set paths this CPU runs and the one `auto` picks.
//!
//! `cargo run --release --example isa`

fn main() {
    let available: Vec<&str> = pbgi::Isa::available().iter().map(|i| i.name()).collect();
    println!(
        "{}: best path {}, available {}",
        std::env::consts::ARCH,
        pbgi::Isa::best(),
        available.join(", ")
    );
    match pbgi::Isa::from_env() {
        Ok(Some(isa)) => println!("PBGI_ISA forces {isa}"),
        Ok(None) => {}
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
