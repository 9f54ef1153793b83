#!/usr/bin/env bash
# Install the system libraries treebook's wheels need, only when missing (open3d needs libusb-1.0).
set -u
missing=()
ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so.0' || missing+=(libusb-1.0-0)
[ ${#missing[@]} -eq 0 ] && exit 0
echo "installing system packages: ${missing[*]}"
if ! command -v apt-get >/dev/null; then
  echo "warning: no apt-get; install ${missing[*]} with your package manager (open3d needs it)" >&2; exit 0
fi
sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
$sudo apt-get install -y -q "${missing[@]}" >/dev/null 2>&1 || { $sudo apt-get update -q >/dev/null 2>&1 && $sudo apt-get install -y -q "${missing[@]}" >/dev/null; } \
  || echo "warning: could not install ${missing[*]}; open3d will not import" >&2
exit 0
