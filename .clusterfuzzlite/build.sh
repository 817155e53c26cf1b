#!/bin/bash -eu
# Builds every cargo-fuzz target with the sanitizer ClusterFuzzLite asks
# for, and ships each target's seed corpus and dictionary next to it.
cd "$SRC/ppmc/fuzz"
cargo fuzz build -O
out_dir=target/x86_64-unknown-linux-gnu/release
for target in $(cargo fuzz list); do
    cp "$out_dir/$target" "$OUT/"
    if [ -d "corpus/$target" ]; then
        (cd "corpus/$target" && zip -q -r "$OUT/${target}_seed_corpus.zip" .)
    fi
    if [ -f "$target.dict" ]; then
        cp "$target.dict" "$OUT/$target.dict"
    fi
done
