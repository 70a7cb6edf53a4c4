#!/bin/sh
# What `cargo build --release --features v4l` needs on a Debian or Ubuntu
# robot laptop: libclang (the Video4Linux bindings are generated at build
# time) and the kernel's userspace headers.
set -eu
sudo apt-get update
sudo apt-get install -y libclang-dev linux-libc-dev
