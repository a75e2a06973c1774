//! Compiles the C++ facade in cpp/ against Debian's Simbody 3.7.
//!
//! Simbody is found through pkg-config (`simbody.pc`, from `libsimbody-dev`).
//! Debian builds Simbody without `-DNDEBUG`, and SimTK headers change class
//! layouts with NDEBUG, so the facade must be compiled with the same setting
//! as the library it links; we detect it from a symbol only assert-enabled
//! builds export.

fn main() {
    println!("cargo:rerun-if-changed=src/simbody.rs");
    println!("cargo:rerun-if-changed=cpp/leap_simbody.h");
    println!("cargo:rerun-if-changed=cpp/leap_simbody.cpp");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");

    let simbody = match pkg_config::Config::new()
        .atleast_version("3.7")
        .cargo_metadata(true)
        .probe("simbody")
    {
        Ok(lib) => lib,
        Err(e) => {
            eprintln!(
                "\nleap needs Simbody 3.7 and pkg-config.\n\
                 On Debian or Ubuntu install them with:\n\n    \
                 sudo apt-get install -y libsimbody-dev pkg-config\n\n\
                 (pkg-config said: {e})\n"
            );
            std::process::exit(1);
        }
    };

    let mut build = cxx_build::bridge("src/simbody.rs");
    build
        .file("cpp/leap_simbody.cpp")
        // simbody.pc says -std=c++11; Simbody's headers compile as C++17.
        .std("c++17")
        .flag_if_supported("-O2")
        .flag_if_supported("-Wno-unused-parameter");
    for inc in &simbody.include_paths {
        // -isystem silences warnings from Simbody's own headers.
        build.flag(format!("-isystem{}", inc.display()));
    }
    let lib = simbody
        .link_paths
        .iter()
        .map(|d| d.join("libSimTKcommon.so"))
        .find(|p| p.exists());
    let debug_abi = match &lib {
        Some(path) => {
            println!("cargo:rerun-if-changed={}", path.display());
            let bytes = std::fs::read(path).unwrap_or_default();
            let sym: &[u8] =
                b"_ZN5SimTK14CacheEntryInfo26recordPrerequisiteVersionsERKNS_9StateImplE";
            bytes.windows(sym.len()).any(|w| w == sym)
        }
        // Debian's layout: assume its (assert-enabled) build.
        None => true,
    };
    if !debug_abi {
        build.define("NDEBUG", None);
    }
    build.compile("leap_simbody");
}
