//! Compiles the protocol with protox (a pure-Rust protobuf compiler), so building needs no protoc.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let proto = "amorph/v1/evaluation.proto";
    println!("cargo:rerun-if-changed={proto}");
    let descriptors = protox::compile([proto], ["."])?;
    tonic_prost_build::configure()
        .build_client(true)
        .build_server(true)
        .compile_fds(descriptors)?;
    Ok(())
}
