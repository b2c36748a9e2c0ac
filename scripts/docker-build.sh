#!/usr/bin/env bash
# Build the aerotrack container image with podman, check that it holds none of the host's
# proxy CAs or proxy settings, and smoke-test it: `aerotrack --help`, the sharp_turn demo
# (`aerotrack sim --scenario sharp_turn`, must print "success") and one MoveNet detection on the
# sprite photo (the models and the photo are in the image).
#
# No Docker engine and no container registry are needed: the `debian:bookworm` base image is
# bootstrapped locally with debootstrap (minbase, same Debian mirror as this host's apt
# sources) and imported into podman. Every step is idempotent; a second run only rebuilds what
# changed (podman layer cache) and prints each phase's time.
#
# Behind a TLS-inspecting proxy: the host's CA bundle (plus $NODE_EXTRA_CA_CERTS if set) reaches
# the build as the build secret `build-ca` (podman build --secret; the Dockerfile mounts it with
# RUN --mount=type=secret for apt and npm only), never as a layer; http_proxy, https_proxy and
# no_proxy (either case) are passed to every RUN by podman and are not kept in the image.
#
# Usage: scripts/docker-build.sh            (from any directory; needs root or sudo)
#
# Environment overrides:
#   AEROTRACK_IMAGE            image tag to build (default aerotrack:latest)
#   AEROTRACK_CONTAINER_STATE  state dir: podman config, storage, debootstrap tree
#                              (default /var/tmp/aerotrack-docker)
#   AEROTRACK_STORAGE_DRIVER   overlay | vfs (default: overlay if it can be mounted here, else vfs)
#   AEROTRACK_BUILD_ISOLATION  oci | chroot (default oci, i.e. runc)
#   AEROTRACK_BUILD_CA         PEM bundle the build trusts (default: $SSL_CERT_FILE or
#                              /etc/ssl/certs/ca-certificates.crt, plus $NODE_EXTRA_CA_CERTS)
#   DEBIAN_MIRROR              Debian mirror for debootstrap (default: taken from apt sources)
#
# To use the same podman storage by hand afterwards:
#   export CONTAINERS_CONF=$AEROTRACK_CONTAINER_STATE/conf/containers.conf
#   export CONTAINERS_STORAGE_CONF=$AEROTRACK_CONTAINER_STATE/conf/storage.conf
#   podman images
set -euo pipefail

SCRIPT_DIR=$(cd -- "$(dirname -- "${BASH_SOURCE[0]}")" && pwd)
REPO_ROOT=$(cd -- "$SCRIPT_DIR/.." && pwd)
cd "$REPO_ROOT"

IMAGE=${AEROTRACK_IMAGE:-aerotrack:latest}
STATE_DIR=${AEROTRACK_CONTAINER_STATE:-/var/tmp/aerotrack-docker}
ISOLATION=${AEROTRACK_BUILD_ISOLATION:-oci}
SUITE=bookworm
BASE_IMAGE=docker.io/library/debian:$SUITE

SUDO=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "error: run as root (or install sudo)" >&2; exit 1; }
  # shellcheck disable=SC2054  # the comma is sudo syntax, not an array separator
  SUDO=(sudo --preserve-env=CONTAINERS_CONF,CONTAINERS_STORAGE_CONF,http_proxy,https_proxy,no_proxy,HTTP_PROXY,HTTPS_PROXY,NO_PROXY)
fi

T_START=$SECONDS
PHASE_NAME=""
PHASE_T0=0
declare -a SUMMARY=()
phase() {  # phase NAME: end the current phase (printing its time) and start the next one
  local now=$SECONDS
  if [[ -n $PHASE_NAME ]]; then
    local line
    line=$(printf '%-12s %4ds' "$PHASE_NAME" $((now - PHASE_T0)))
    SUMMARY+=("$line")
    echo "=== [$PHASE_NAME] done in $((now - PHASE_T0))s"
  fi
  PHASE_NAME=$1
  PHASE_T0=$now
  [[ -n $PHASE_NAME ]] && echo "=== [$PHASE_NAME] ..."
  return 0
}

# --- 1. tools ---------------------------------------------------------------------------------
phase tools
need=()
for pair in podman:podman buildah:buildah debootstrap:debootstrap runc:runc; do
  command -v "${pair%%:*}" >/dev/null || need+=("${pair#*:}")
done
if ((${#need[@]})); then
  echo "installing: ${need[*]}"
  "${SUDO[@]}" apt-get update -q
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${need[@]}"
fi

# --- 2. podman configuration (private to this script; /etc/containers is left alone) ----------
phase configure
CONF_DIR=$STATE_DIR/conf
"${SUDO[@]}" mkdir -p "$CONF_DIR"

driver=${AEROTRACK_STORAGE_DRIVER:-}
if [[ -z $driver ]]; then
  # overlay works on a real kernel with ext4/xfs underneath; nested inside an overlayfs-based
  # container it usually does not, then fall back to the slow but always-working vfs driver.
  probe=$STATE_DIR/overlay-probe
  "${SUDO[@]}" mkdir -p "$probe"/{lower,upper,work,merged}
  if "${SUDO[@]}" mount -t overlay overlay \
       -o "lowerdir=$probe/lower,upperdir=$probe/upper,workdir=$probe/work" "$probe/merged" \
       2>/dev/null; then
    "${SUDO[@]}" umount "$probe/merged"
    driver=overlay
  else
    driver=vfs
  fi
  "${SUDO[@]}" rm -rf "$probe"
fi

# The container may not raise rlimits above this host's hard limits (the sandbox forbids it),
# and podman's defaults (nofile/nproc up to 1048576/4194304) are higher: cap them.
hard_nofile=$(ulimit -Hn); [[ $hard_nofile == unlimited ]] && hard_nofile=1048576
hard_nproc=$(ulimit -Hu);  [[ $hard_nproc == unlimited ]] && hard_nproc=1048576
nofile=$((hard_nofile < 65536 ? hard_nofile : 65536))
nproc=$((hard_nproc < 8192 ? hard_nproc : 8192))

"${SUDO[@]}" tee "$CONF_DIR/storage.conf" >/dev/null <<EOF
# generated by scripts/docker-build.sh
[storage]
driver = "$driver"
graphroot = "$STATE_DIR/storage-$driver"
runroot = "/run/aerotrack-containers/storage-$driver"
EOF
"${SUDO[@]}" tee "$CONF_DIR/containers.conf" >/dev/null <<EOF
# generated by scripts/docker-build.sh
[containers]
netns = "host"
default_ulimits = ["nofile=$nofile:$nofile", "nproc=$nproc:$nproc"]

[engine]
runtime = "runc"
cgroup_manager = "cgroupfs"
events_logger = "file"
EOF
export CONTAINERS_CONF=$CONF_DIR/containers.conf
export CONTAINERS_STORAGE_CONF=$CONF_DIR/storage.conf
PODMAN=("${SUDO[@]}" podman --runtime runc --cgroup-manager cgroupfs --events-backend file)
echo "storage driver: $driver, isolation: $ISOLATION, ulimits nofile=$nofile nproc=$nproc"

# --- 3. base image: debootstrap debian:bookworm and import it -----------------------------
phase bootstrap
detect_mirror() {  # first enabled apt source for the main Debian archive (not security)
  local f uri
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [[ -r $f ]] || continue
    uri=$(awk '$1 == "deb" { for (i = 2; i <= NF; i++) if ($i ~ /^[a-z+]+:\/\//) { print $i; break } }' "$f" \
            | grep -E '/debian/?$' | head -n1 || true)
    [[ -n $uri ]] && { echo "${uri%/}"; return; }
  done
  for f in /etc/apt/sources.list.d/*.sources; do
    [[ -r $f ]] || continue
    uri=$(awk 'tolower($1) == "uris:" { for (i = 2; i <= NF; i++) print $i }' "$f" \
            | grep -E '/debian/?$' | head -n1 || true)
    [[ -n $uri ]] && { echo "${uri%/}"; return; }
  done
  echo http://deb.debian.org/debian
}

if "${PODMAN[@]}" image exists "$BASE_IMAGE"; then
  echo "$BASE_IMAGE already present, skipping debootstrap"
else
  mirror=${DEBIAN_MIRROR:-$(detect_mirror)}
  security=${mirror%/debian}/debian-security
  rootfs=$STATE_DIR/rootfs-$SUITE
  if [[ ! -e $rootfs/.debootstrap-complete ]]; then
    echo "debootstrap --variant=minbase $SUITE from $mirror"
    "${SUDO[@]}" rm -rf "$rootfs"
    "${SUDO[@]}" debootstrap --variant=minbase "$SUITE" "$rootfs" "$mirror"
    # Same apt sources layout as the official image (including updates and security).
    "${SUDO[@]}" rm -f "$rootfs/etc/apt/sources.list"
    "${SUDO[@]}" tee "$rootfs/etc/apt/sources.list.d/debian.sources" >/dev/null <<EOF
Types: deb
URIs: $mirror
Suites: $SUITE $SUITE-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: $security
Suites: $SUITE-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    # apt settings of the official image: no package caches or translations kept in layers.
    "${SUDO[@]}" tee "$rootfs/etc/apt/apt.conf.d/docker-clean" >/dev/null <<'EOF'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
EOF
    echo 'Acquire::Languages "none";' \
      | "${SUDO[@]}" tee "$rootfs/etc/apt/apt.conf.d/docker-no-languages" >/dev/null
    echo 'Apt::AutoRemove::SuggestsImportant "false";' \
      | "${SUDO[@]}" tee "$rootfs/etc/apt/apt.conf.d/docker-autoremove-suggests" >/dev/null
    "${SUDO[@]}" rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*.bin \
      "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/log/*.log "$rootfs"/var/log/apt/*
    "${SUDO[@]}" touch "$rootfs/.debootstrap-complete"
  fi
  echo "importing $rootfs as $BASE_IMAGE"
  "${SUDO[@]}" tar --numeric-owner --exclude=./.debootstrap-complete -C "$rootfs" -c . \
    | "${PODMAN[@]}" import --change 'CMD ["bash"]' - "$BASE_IMAGE"
fi
# `FROM debian:bookworm` resolves to docker.io/library/debian:bookworm; localhost/ as well for
# anyone who spells it that way.
"${PODMAN[@]}" tag "$BASE_IMAGE" "localhost/debian:$SUITE"

# --- 4. build ---------------------------------------------------------------------------------
phase build
# The CAs the build trusts, handed over as a build secret (mounted only into the RUNs that fetch:
# apt and npm), so a TLS-inspecting proxy's CA works inside without ever entering a layer. The
# secret's content is not part of the layer cache key: changing the CAs rebuilds nothing.
ca_bundle=$STATE_DIR/build-ca.pem
ca_sources=()
if [[ -n ${AEROTRACK_BUILD_CA:-} ]]; then
  [[ -r $AEROTRACK_BUILD_CA ]] || { echo "error: AEROTRACK_BUILD_CA=$AEROTRACK_BUILD_CA: not readable" >&2; exit 1; }
  ca_sources=("$AEROTRACK_BUILD_CA")
else
  for f in "${SSL_CERT_FILE:-/etc/ssl/certs/ca-certificates.crt}" "${NODE_EXTRA_CA_CERTS:-}"; do
    [[ -n $f && -r $f ]] || continue
    for g in "${ca_sources[@]}"; do [[ $f -ef $g ]] && continue 2; done
    ca_sources+=("$f")
  done
fi
secret_args=()
if ((${#ca_sources[@]})); then
  cat "${ca_sources[@]}" | "${SUDO[@]}" install -m 600 /dev/stdin "$ca_bundle"
  secret_args=(--secret "id=build-ca,src=$ca_bundle")
  echo "build secret build-ca: ${ca_sources[*]} ($(cat "${ca_sources[@]}" | grep -c 'BEGIN CERTIFICATE') certificates)"
else
  echo "no CA bundle found: the build uses the image's stock CAs"
fi
proxies=$(env | grep -iE '^(https?|no)_proxy=' | cut -d= -f1 | tr '\n' ' ' || true)
echo "proxy variables passed to the build: ${proxies:-none}"
"${PODMAN[@]}" build --pull=never --isolation "$ISOLATION" --network host "${secret_args[@]}" \
  -f "$REPO_ROOT/Dockerfile" -t "$IMAGE" "$REPO_ROOT"
"${PODMAN[@]}" image ls "$IMAGE"

# --- 5. verify: no host CA and no proxy setting in the image -------------------------------------
phase verify
image_id=$("${PODMAN[@]}" image inspect --format '{{.Id}}' "$IMAGE")
# The host's own CAs (the proxy's among them): certificates of the bundle that are not in
# Debian's ca-certificates, each known by the 2nd base64 line of its PEM body.
pem_line2() { awk '/-----BEGIN CERTIFICATE-----/ { n = 0; next } /-----END/ { next } ++n == 2' "$@"; }
local_cas=$STATE_DIR/local-ca-lines.txt
if ((${#ca_sources[@]})); then
  pem_line2 "${ca_sources[@]}" | grep -vxF -f <(pem_line2 /usr/share/ca-certificates/mozilla/*.crt 2>/dev/null || true) \
    | "${SUDO[@]}" tee "$local_cas" >/dev/null || true
else
  "${SUDO[@]}" truncate -s 0 "$local_cas"
fi
stamp="$image_id $(sha256sum <"$local_cas" | cut -d' ' -f1)"
if [[ -f $STATE_DIR/verified && $(<"$STATE_DIR/verified") == "$stamp" ]]; then
  echo "image $image_id already verified"
else
  image_env=$("${PODMAN[@]}" image inspect --format '{{range .Config.Env}}{{println .}}{{end}}' "$IMAGE")
  if grep -iE '^(https?_proxy|no_proxy|node_extra_ca_certs|ssl_cert_file|npm_config_[a-z_]*)=' <<<"$image_env"; then
    echo "error: $IMAGE keeps the build's proxy/CA environment (above)" >&2; exit 1
  fi
  n_local=$(grep -c . "$local_cas" || true)
  if ((n_local > 0)); then
    mnt=$("${PODMAN[@]}" image mount "$IMAGE")
    set +e
    found=$("${SUDO[@]}" grep -rlF -f "$local_cas" "$mnt")
    set -e
    "${PODMAN[@]}" image unmount "$IMAGE" >/dev/null
    if [[ -n $found ]]; then
      echo "error: $IMAGE holds a CA of this host's bundle that is not in Debian's ca-certificates:" >&2
      echo "${found//$mnt/}" >&2
      exit 1
    fi
  fi
  echo "$IMAGE: no proxy/CA variable in its ENV, none of this host's $n_local own CA(s) in its files"
  echo "$stamp" | "${SUDO[@]}" tee "$STATE_DIR/verified" >/dev/null
fi

# --- 6. smoke test ----------------------------------------------------------------------------
phase run
smoke() {  # smoke ARGS...: run the image with ARGS, print its output, fail on a non-zero exit
  local out rc=0
  out=$("${PODMAN[@]}" run --rm "$IMAGE" "$@" 2>&1) || rc=$?
  printf '%s\n' "$out"
  if ((rc != 0)); then
    echo "error: 'podman run --rm $IMAGE $*' exited with $rc" >&2
    exit "$rc"
  fi
  SMOKE_OUT=$out
}
smoke --help >/dev/null
echo "'aerotrack --help' exited 0"
smoke sim --scenario sharp_turn --out /tmp/demo
first=$(head -n1 <<<"$SMOKE_OUT")
if [[ ! $first =~ ^sharp_turn\ seed\ [0-9]+\ \(.*\):\ success$ ]]; then
  echo "error: the sharp_turn demo in $IMAGE did not report success: $first" >&2
  exit 1
fi
smoke detect /usr/share/doc/opencv-doc/examples/data/basketball1.png
grep -q '1 person(s)' <<<"$SMOKE_OUT" \
  || { echo "error: the detector in $IMAGE found no person in basketball1.png" >&2; exit 1; }
echo "smoke test: $first"

phase ""
size=$("${PODMAN[@]}" image inspect --format '{{.Size}}' "$IMAGE")
echo "=== $IMAGE: $image_id, $((size / 1000000)) MB"
echo "=== timings"
printf '  %s\n' "${SUMMARY[@]}"
printf '  %-12s %4ds\n' total $((SECONDS - T_START))
