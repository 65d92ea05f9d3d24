#!/usr/bin/env bash
# A throwaway PostgreSQL server for the tests: initdb in a temporary
# directory, start on a free local port, print its URL on stdout.
#
#   scripts/pg-test-server.sh WATCH_PID
#
# The server stops and its directory is removed when process WATCH_PID
# (the test process) ends. As root, the server runs as the unprivileged
# user `postgres` (or `nobody`): PostgreSQL refuses to run as root.
# The binaries are taken from $INCAL_PG_BIN, else /usr/lib/postgresql/15/bin.
set -euo pipefail
watch=${1:?usage: pg-test-server.sh WATCH_PID}
bin=${INCAL_PG_BIN:-/usr/lib/postgresql/15/bin}
if [ ! -x "$bin/postgres" ] || [ ! -x "$bin/initdb" ]; then
    echo "pg-test-server: no PostgreSQL server binaries in $bin (install postgresql-15, or set INCAL_PG_BIN)" >&2
    exit 1
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/incal-pg.XXXXXX")
as=()
if [ "$(id -u)" = 0 ]; then
    user=postgres
    id "$user" >/dev/null 2>&1 || user=nobody
    chown "$user" "$dir"
    as=(setpriv --reuid="$user" --regid="$(id -g "$user")" --clear-groups --)
fi
chmod 700 "$dir"
if ! "${as[@]}" "$bin/initdb" -D "$dir/data" -U incal --auth=trust -E UTF8 --locale=C \
    >"$dir/initdb.log" 2>&1; then
    echo "pg-test-server: initdb failed:" >&2
    cat "$dir/initdb.log" >&2
    rm -rf "$dir"
    exit 1
fi
port=
for _ in $(seq 1 20); do
    try=$((20000 + RANDOM % 30000))
    if "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
        -o "-p $try -k $dir -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200" \
        start >/dev/null 2>&1; then
        port=$try
        break
    fi
done
if [ -z "$port" ]; then
    echo "pg-test-server: the server did not start:" >&2
    tail -n 20 "$dir/server.log" >&2 || true
    rm -rf "$dir"
    exit 1
fi
# The watchdog: stop the server once the test process is gone.
stop="${as[*]} $bin/pg_ctl -D $dir/data -m immediate stop"
setsid bash -c "while kill -0 $watch 2>/dev/null; do sleep 1; done; $stop >/dev/null 2>&1; rm -rf $dir" \
    </dev/null >/dev/null 2>&1 &
echo "postgresql://incal@127.0.0.1:$port/postgres"
