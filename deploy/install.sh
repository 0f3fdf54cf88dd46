#!/bin/sh
# install.sh — installs a built isomesh as a system service: the programs, the viewer and the
# documents under /usr/local, the settings in /etc/isomesh, the systemd units, the nginx site
# (and the Redis settings when Redis is there), then starts the daemon and reloads nginx.
#
#   deploy/install.sh [--build DIR] [--destdir DIR] [--no-start]
#
#   --build DIR    the build to install [build/release]; build it first: make build web-deps
#   --destdir DIR  install under DIR instead of / (packaging, tests); implies --no-start
#   --no-start     copy files only; do not touch systemd or nginx
#
# Existing settings files are kept: the new version is written beside them as *.new.
set -eu

here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/.." && pwd)
build=build/release
destdir=""
start=1
while [ $# -gt 0 ]; do
    case "$1" in
        --build) build=$2; shift 2 ;;
        --destdir) destdir=$2; start=0; shift 2 ;;
        --no-start) start=0; shift ;;
        -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
        *) echo "install.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
    esac
done
case "$build" in /*) ;; *) build="$src/$build" ;; esac

lib="$destdir/usr/local/lib/isomesh"
share="$destdir/usr/local/share/isomesh"
etc="$destdir/etc/isomesh"
units="$destdir/etc/systemd/system"

for f in "$build/isomeshd" "$build/isomesh"; do
    [ -x "$f" ] || { echo "install.sh: $f is missing: run 'make build' first" >&2; exit 1; }
done
[ -d "$src/web/node_modules/three/build" ] ||
    { echo "install.sh: web/node_modules/three is missing: run 'make web-deps' first" >&2; exit 1; }
if [ -z "$destdir" ] && [ "$(id -u)" != 0 ]; then
    echo "install.sh: run as root (or with --destdir DIR)" >&2
    exit 1
fi

# A settings file the administrator may have edited: never overwritten.
install_config() { # SOURCE TARGET
    if [ -e "$2" ] && ! cmp -s "$1" "$2"; then
        install -m 0644 "$1" "$2.new"
        echo "install.sh: kept your $2; the shipped version is $2.new"
    else
        install -D -m 0644 "$1" "$2"
    fi
}

echo "install.sh: programs -> $lib"
install -d -m 0755 "$lib" "$destdir/usr/local/bin" "$destdir/usr/local/sbin"
install -m 0755 "$build/isomeshd" "$build/isomesh" "$lib/"
ln -sf ../lib/isomesh/isomesh "$destdir/usr/local/bin/isomesh"
ln -sf ../lib/isomesh/isomeshd "$destdir/usr/local/sbin/isomeshd"

echo "install.sh: viewer and documents -> $share"
rm -rf "$share/web"
install -d -m 0755 "$share/web/node_modules/three/examples" "$share/proto" "$share/deploy"
cp -R "$src/web/index.html" "$src/web/style.css" "$src/web/favicon.svg" "$src/web/js" "$share/web/"
cp -R "$src/web/node_modules/three/build" "$src/web/node_modules/three/package.json" \
      "$src/web/node_modules/three/LICENSE" "$share/web/node_modules/three/"
cp -R "$src/web/node_modules/three/examples/jsm" "$share/web/node_modules/three/examples/"
install -m 0644 "$src/proto/openapi.yaml" "$src/proto/request.schema.json" "$share/proto/"
install -m 0644 "$src/deploy/README.md" "$share/deploy/"
chmod -R u=rwX,go=rX "$share"

echo "install.sh: settings -> $etc, units -> $units"
install -d -m 0755 "$etc" "$units"
install_config "$src/deploy/isomeshd.conf" "$etc/isomeshd.conf"
# The tokens file holds only hashes; the daemon's dynamic user must be able to read it.
[ -e "$etc/tokens" ] || install -m 0644 /dev/null "$etc/tokens"
for u in isomeshd.service isomeshd@.service isomesh.slice; do
    install -m 0644 "$src/deploy/systemd/$u" "$units/$u"
done

if [ -d /etc/nginx ] || [ -n "$destdir" ]; then
    echo "install.sh: nginx site -> $destdir/etc/nginx/sites-available/isomesh"
    install -d -m 0755 "$destdir/etc/nginx/sites-available" "$destdir/etc/nginx/sites-enabled"
    install_config "$src/deploy/nginx/isomesh.conf" "$destdir/etc/nginx/sites-available/isomesh"
    ln -sf ../sites-available/isomesh "$destdir/etc/nginx/sites-enabled/isomesh"
    # nginx's copy of the meshes served by key (proxy_cache_path in the site); its workers
    # (www-data on Debian) write it
    install -d -m 0700 "$destdir/var/cache/nginx/isomesh"
    [ -n "$destdir" ] || chown www-data: /var/cache/nginx/isomesh 2>/dev/null || true
    # Debian's example site also claims port 80.
    if [ -L "$destdir/etc/nginx/sites-enabled/default" ]; then
        rm -f "$destdir/etc/nginx/sites-enabled/default"
        echo "install.sh: disabled nginx's default site"
    fi
fi
if [ -d /etc/redis ] || [ -n "$destdir" ]; then
    install -d -m 0755 "$destdir/etc/redis"
    install_config "$src/deploy/redis/isomesh.conf" "$destdir/etc/redis/isomesh.conf"
fi

if [ "$start" = 0 ]; then
    echo "install.sh: files installed${destdir:+ under $destdir}"
    exit 0
fi
if ! command -v systemctl >/dev/null 2>&1 || [ ! -d /run/systemd/system ]; then
    echo "install.sh: systemd is not running here; start $lib/isomeshd --config $etc/isomeshd.conf yourself"
    exit 0
fi
systemctl daemon-reload
systemctl enable --now isomeshd.service
if command -v nginx >/dev/null 2>&1; then
    nginx -t
    systemctl reload-or-restart nginx.service
fi
echo "install.sh: isomesh is running: http://$(hostname -f 2>/dev/null || hostname)/"
echo "install.sh: status: systemctl status isomeshd; log: journalctl -u isomeshd -f"
