// A shared library loaded when first needed instead of linked: a command that does not use it
// does not map and relocate it at start-up (issue 17: libpq's dependency tree cost every rig
// command 4-5 ms). Used for libpq (rig/report/db.cpp) and libcrypto (rig/seal/seal.cpp).
#pragma once
#include <dlfcn.h>

namespace rig {

class LazyLibrary {
 public:
  explicit LazyLibrary(const char* soname) : handle_(::dlopen(soname, RTLD_NOW | RTLD_LOCAL)) {}
  // Sets `fn` to the library's symbol `name` (null when missing; ok() is then false).
  template <class Fn>
  void get(Fn& fn, const char* name) {
    fn = handle_ ? reinterpret_cast<Fn>(::dlsym(handle_, name)) : nullptr;
    ok_ = ok_ && fn != nullptr;
  }
  // Loaded, and every symbol asked for found.
  bool ok() const { return handle_ != nullptr && ok_; }

 private:
  void* handle_;
  bool ok_ = true;
};

}  // namespace rig
