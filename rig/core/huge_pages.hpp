// Asks the kernel for transparent huge pages under a large buffer before it is first written.
// Each 4 KiB page of a fresh allocation costs a page fault on its first touch; on the VMs CI and
// the developers run on a fault costs 10-25 us (2026-11-28: the `paper` procedure took 85 000 of
// them, 0.8 s of its system time). One 2 MiB page takes 512 of them in one fault.
#pragma once
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>

namespace rig {

// Advises the whole 2 MiB pages inside [p, p + bytes) (advisory: a kernel without THP, or one
// set to `never`, leaves them 4 KiB, which only costs speed). Call it before the first write: a
// page already touched stays 4 KiB until khugepaged collapses it.
inline void advise_huge_pages(const void* p, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  const auto a = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) / kHuge * kHuge;
  const auto b = (reinterpret_cast<std::uintptr_t>(p) + bytes) / kHuge * kHuge;
  if (b > a) ::madvise(reinterpret_cast<void*>(a), b - a, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

}  // namespace rig
