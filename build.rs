//! Finds Debian's Embree (4 first, then 3), compiles our C shim for that major,
//! and generates Rust bindings from the shim's own header with bindgen.
//!
//! Search order for `embree{4,3}/rtcore_config.h`: `$EMBREE_DIR/include` (when
//! set, only there), then `/usr/local/include`, then `/usr/include`.

use std::env;
use std::path::{Path, PathBuf};

/// One Embree installation: its major version and the include directory that
/// holds `embree<major>/`.
struct Embree {
    major: u32,
    include_dir: PathBuf,
    lib_dir: Option<PathBuf>,
}

fn find_embree() -> Option<Embree> {
    let roots: Vec<PathBuf> = match env::var_os("EMBREE_DIR") {
        Some(dir) => vec![PathBuf::from(dir)],
        None => vec![PathBuf::from("/usr/local"), PathBuf::from("/usr")],
    };
    for major in [4, 3] {
        for root in &roots {
            let include_dir = root.join("include");
            if include_dir.join(format!("embree{major}/rtcore_config.h")).is_file() {
                let lib_dir = [root.join("lib"), root.join("lib64")].into_iter().find(|dir| has_library(dir, major));
                return Some(Embree { major, include_dir, lib_dir });
            }
        }
    }
    None
}

fn has_library(dir: &Path, major: u32) -> bool {
    dir.join(format!("libembree{major}.so")).exists()
}

fn main() {
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo:rerun-if-changed=src/embree/shim.c");
    println!("cargo:rerun-if-changed=src/embree/shim.h");
    for root in ["/usr/local/include", "/usr/include"] {
        for major in [3, 4] {
            println!("cargo:rerun-if-changed={root}/embree{major}/rtcore_config.h");
        }
    }

    let Some(embree) = find_embree() else {
        eprintln!(
            "\nerror: Intel Embree was not found.\n\
             lightcuts needs Embree 3 or 4 headers (embree4/rtcore_config.h or \
             embree3/rtcore_config.h) under $EMBREE_DIR/include, /usr/local/include \
             or /usr/include.\n\
             On Debian or Ubuntu install it with:  sudo apt-get install libembree-dev\n\
             (or run ci/setup.sh, which installs every package the build needs).\n"
        );
        std::process::exit(1);
    };

    cc::Build::new()
        .file("src/embree/shim.c")
        .include(&embree.include_dir)
        .define("LC_EMBREE_MAJOR", embree.major.to_string().as_str())
        .flag_if_supported("-std=c11")
        .flag_if_supported("-Wall")
        .flag_if_supported("-Wextra")
        .warnings_into_errors(true)
        .compile("lightcuts_embree_shim");

    if let Some(lib_dir) = &embree.lib_dir {
        println!("cargo:rustc-link-search=native={}", lib_dir.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree{}", embree.major);
    println!("cargo:rustc-cfg=embree_major=\"{}\"", embree.major);
    println!("cargo::rustc-check-cfg=cfg(embree_major, values(\"3\", \"4\"))");
    println!("cargo:rustc-env=LIGHTCUTS_EMBREE_MAJOR={}", embree.major);

    // Only our own header goes through bindgen: its types are plain C and the
    // same for both Embree majors, and bindgen's layout tests check them.
    let bindings = bindgen::Builder::default()
        .header("src/embree/shim.h")
        .allowlist_function("lc_.*")
        .allowlist_type("Lc.*")
        .allowlist_var("LC_.*")
        .layout_tests(true)
        .derive_default(true)
        .generate()
        .unwrap_or_else(|error| {
            eprintln!(
                "\nerror: bindgen could not read src/embree/shim.h: {error}\n\
                 bindgen needs libclang: sudo apt-get install libclang-dev\n"
            );
            std::process::exit(1);
        });
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    bindings.write_to_file(out.join("shim_bindings.rs")).expect("OUT_DIR is writable");
}
