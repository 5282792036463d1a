//! With the `denoise` feature and `OIDN_DIR` set (the folder whose `lib`
//! holds Intel Open Image Denoise, as `scripts/oidn.sh` prints it), every
//! binary, test and example finds that library at run time without
//! `LD_LIBRARY_PATH`: the `oidn` crate links it but sets no run path.

fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    println!("cargo:rerun-if-changed=build.rs");
    let denoise = std::env::var_os("CARGO_FEATURE_DENOISE").is_some();
    let unix = std::env::var("CARGO_CFG_TARGET_FAMILY").is_ok_and(|f| f == "unix");
    if let (true, true, Some(dir)) = (denoise, unix, std::env::var_os("OIDN_DIR")) {
        let lib = std::path::Path::new(&dir).join("lib");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
