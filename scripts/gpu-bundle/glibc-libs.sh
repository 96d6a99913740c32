# glibc's own libraries: the one set that a bundle of scripts/gpu-check takes from the machine it
# runs on, since that machine's programs and GPU driver share them (and its loader, ld-linux, must
# match its libc). Sourced by scripts/gpu-check and by the bundle's run.
is_glibc_lib() {
  case $1 in
    linux-vdso.so.*|ld-linux*.so.*|libc.so.*|libm.so.*|libpthread.so.*|libdl.so.*|librt.so.*| \
    libresolv.so.*|libutil.so.*|libanl.so.*|libmvec.so.*) return 0 ;;
  esac
  return 1
}
