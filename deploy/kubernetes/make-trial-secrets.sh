#!/usr/bin/env bash
# FOR TRIALS ONLY: writes the files the Secrets of overlays/trial are made from, in this
# folder (never committed: secrets/ folders ignore everything):
#   base/secrets/ca.crt, ca.key        a CA of its own; clients trust it (fenestra --tls-ca)
#   base/secrets/tls.crt, tls.key      fenestrad's certificate, signed by that CA, for the
#                                      Service's names in NAMESPACE and for localhost
#                                      (kubectl port-forward)
#   components/trial-postgresql/secrets/postgresql.env   a random database password
#   base/secrets/store.env             the store URL of the trial database, with it
# Usage: make-trial-secrets.sh [NAMESPACE]   (default fenestra). Refuses to overwrite.
set -euo pipefail
namespace="${1:-fenestra}"
here="$(cd "$(dirname "$0")" && pwd)"
secrets="$here/base/secrets"
database="$here/components/trial-postgresql/secrets"
for file in "$secrets"/{ca.crt,ca.key,tls.crt,tls.key,store.env} "$database/postgresql.env"; do
  if [ -e "$file" ]; then
    echo "make-trial-secrets.sh: $file exists; remove it to make new secrets" >&2
    exit 1
  fi
done
umask 077
mkdir -p "$secrets" "$database"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The CA and fenestrad's certificate (EC P-256, 1 year)
key="-newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes"
names="DNS:fenestrad,DNS:fenestrad.$namespace,DNS:fenestrad.$namespace.svc"
names="$names,DNS:fenestrad.$namespace.svc.cluster.local,DNS:localhost,IP:127.0.0.1"
openssl req -x509 $key -keyout "$secrets/ca.key" -out "$secrets/ca.crt" -days 365 \
  -subj "/CN=fenestra trial CA" 2>"$work/log" || { cat "$work/log" >&2; exit 1; }
openssl req $key -keyout "$secrets/tls.key" -out "$work/tls.csr" -subj "/CN=fenestrad" \
  -addext "subjectAltName=$names" 2>"$work/log" || { cat "$work/log" >&2; exit 1; }
openssl x509 -req -in "$work/tls.csr" -CA "$secrets/ca.crt" -CAkey "$secrets/ca.key" \
  -CAcreateserial -CAserial "$work/ca.srl" -days 365 -copy_extensions copy \
  -out "$secrets/tls.crt" 2>"$work/log" || { cat "$work/log" >&2; exit 1; }

# The trial database's password and the store URL that uses it
password="$(openssl rand -hex 24)"
echo "POSTGRES_PASSWORD=$password" >"$database/postgresql.env"
echo "FENESTRA_STORE=postgresql://fenestra:$password@fenestra-postgresql:5432/fenestra" \
  >"$secrets/store.env"
echo "made the trial secrets for namespace $namespace; clients trust $secrets/ca.crt"
