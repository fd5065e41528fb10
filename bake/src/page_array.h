// Large bake buffers (sort runs, file blocks, the in-core vertex array) mapped straight from
// the kernel and unmapped when freed, so the pages they held leave the resident set at once.
//
// Why not new[]: glibc serves blocks above 128 KiB from the heap once a freed mmapped block has
// raised its dynamic mmap threshold (up to 32 MiB), and a freed heap block below the top stays
// resident. The bake frees its sort buffers stage after stage; through new[] that left about
// 30 MiB of resident holes at 10M triangles, past the --memory budget.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace octolod::bake {

// An uninitialized array of `size()` T, owned; pages count in the RSS once written. Not
// thread-safe (like unique_ptr<T[]>): one owner at a time; distinct elements may be written
// by different threads.
template <typename T>
class PageArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                "PageArray holds raw bytes: no constructors or destructors run");

 public:
  PageArray() = default;
  // Throws std::bad_alloc when the kernel refuses the mapping (as new[] would).
  explicit PageArray(std::size_t count) : size_(count) {
    if (count == 0) return;
    void* p = ::mmap(nullptr, bytes(), PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    data_ = static_cast<T*>(p);
  }
  PageArray(PageArray&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  PageArray& operator=(PageArray&& other) noexcept {
    if (this != &other) {
      reset();
      data_ = std::exchange(other.data_, nullptr);
      size_ = std::exchange(other.size_, 0);
    }
    return *this;
  }
  PageArray(const PageArray&) = delete;
  PageArray& operator=(const PageArray&) = delete;
  ~PageArray() { reset(); }

  // Unmaps the array; empty afterwards.
  void reset() {
    if (data_) ::munmap(data_, bytes());
    data_ = nullptr;
    size_ = 0;
  }

  T* get() const { return data_; }
  std::size_t size() const { return size_; }
  T& operator[](std::size_t i) const { return data_[i]; }
  explicit operator bool() const { return data_ != nullptr; }

 private:
  std::size_t bytes() const { return size_ * sizeof(T); }

  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace octolod::bake
