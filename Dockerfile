# aerotrack container image (multi-stage). Build with scripts/docker-build.sh (podman, no
# registry needed) or any Docker-compatible builder: `docker build -t aerotrack .`
ARG DEBIAN_IMAGE=debian:bookworm

# ---- build: compile, run the unit tests, work out the runtime packages -----------------------
FROM ${DEBIAN_IMAGE} AS build
ENV DEBIAN_FRONTEND=noninteractive
# The one package list (shared with scripts/setup.sh); only it invalidates this layer.
COPY scripts/deps/debian-build.txt /tmp/debian-build.txt
RUN apt-get update \
 && sed -e 's/#.*//' -e 's/[[:space:]]\+$//' /tmp/debian-build.txt | grep -v '^[[:space:]]*$' \
      | xargs apt-get install -y --no-install-recommends \
 && apt-get clean && rm -rf /var/lib/apt/lists/*

WORKDIR /src
# The MoveNet models (npm package -> ONNX, scripts/models): their own layer, rebuilt only when the
# converter changes. models/ is not in the build context (.dockerignore), so COPY . . keeps them.
COPY scripts/models /src/scripts/models
RUN scripts/models/provision.sh && rm -rf .cache /var/lib/apt/lists/*
COPY . .
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \
 && cmake --build build \
 && ctest --test-dir build --output-on-failure -j2 -L unit

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
ENV DEBIAN_FRONTEND=noninteractive
COPY --from=build /tmp/runtime-packages.txt /tmp/runtime-packages.txt
RUN apt-get update \
 && xargs apt-get install -y --no-install-recommends < /tmp/runtime-packages.txt \
 && apt-get clean && rm -rf /var/lib/apt/lists/* /tmp/runtime-packages.txt
COPY --from=build /src/build/bin/aerotrack /usr/local/bin/aerotrack
COPY --from=build /src/config /usr/local/share/aerotrack/config
COPY --from=build /src/models /usr/local/share/aerotrack/models
# The photo the simulator's image-mode camera cuts its person from (not the whole opencv-doc).
COPY --from=build /usr/share/doc/opencv-doc/examples/data/basketball1.png /usr/share/doc/opencv-doc/examples/data/basketball1.png
# Fail the build here, not at first run, if a library is missing.
RUN ! ldd /usr/local/bin/aerotrack | grep 'not found'
ENTRYPOINT ["aerotrack"]
CMD ["--help"]
