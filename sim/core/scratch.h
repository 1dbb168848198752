#pragma once
/// Owned scratch memory with value semantics for the object that holds it: a copy starts
/// without scratch (recreated on demand) and a copy assignment keeps the target's own, so two
/// copies never share buffers and the scratch is never part of the value. A move takes it along.
/// T may be incomplete where a holder is declared: the deleter is fixed where T is created.
#include <cstddef>
#include <memory>

namespace mudcrack {

template <class T>
class Scratch {
public:
    Scratch() = default;
    Scratch(const Scratch&) {}
    Scratch& operator=(const Scratch&) { return *this; }
    Scratch(Scratch&&) noexcept = default;
    Scratch& operator=(Scratch&&) noexcept = default;

    /// The scratch, created empty if there is none (needs T complete).
    T& get_or_create() {
        if (!m_value) m_value = Owner(new T(), [](T* p) { delete p; });
        return *m_value;
    }
    T* get() const { return m_value.get(); }
    T* operator->() const { return m_value.get(); }
    T& operator*() const { return *m_value; }
    explicit operator bool() const { return m_value != nullptr; }
    void reset() { m_value.reset(); }
    friend bool operator==(const Scratch& s, std::nullptr_t) { return !s.m_value; }
    friend bool operator!=(const Scratch& s, std::nullptr_t) { return bool(s.m_value); }

private:
    using Owner = std::unique_ptr<T, void (*)(T*)>;
    Owner m_value{nullptr, [](T*) {}};
};

}  // namespace mudcrack
