// core/expected: a small value-or-error result for the real-time path.
//
// Contract: Expected<T, E> holds either a T or an error code E (an enum of the module
// that produced it). It never allocates and never throws; asking for the value of an
// error (or the error of a value) is a programming bug caught by an assert in debug
// builds. std::expected is C++23; g++ 12 (our compiler) does not ship it.
#pragma once

#include <cassert>
#include <utility>

namespace vp {

template <class E>
struct Unexpected {
  E error;
};

template <class E>
Unexpected<E> unexpected(E error) {
  return Unexpected<E>{error};
}

template <class T, class E>
class Expected {
 public:
  Expected(T value) : value_(std::move(value)), hasValue_(true) {}  // NOLINT: implicit by design
  Expected(Unexpected<E> error) : error_(error.error), hasValue_(false) {}  // NOLINT

  bool hasValue() const { return hasValue_; }
  explicit operator bool() const { return hasValue_; }

  const T& value() const {
    assert(hasValue_);
    return value_;
  }
  T& value() {
    assert(hasValue_);
    return value_;
  }
  const T& operator*() const { return value(); }
  T& operator*() { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

  E error() const {
    assert(!hasValue_);
    return error_;
  }

 private:
  T value_{};
  E error_{};
  bool hasValue_;
};

}  // namespace vp
