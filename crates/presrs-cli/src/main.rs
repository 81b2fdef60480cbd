//! The `presrs` command line.

fn main() {
    println!("presrs");
}
