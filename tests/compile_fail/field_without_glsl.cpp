// Must not compile: a field type with C++ only, given to the GLSL emitter. The test
// (glsl_names_a_type_without_glsl in tests/CMakeLists.txt) asserts the compiler's error names the type.
#include "krs/glsl/emitter.hpp"

struct user_made_field {
    template <class T>
    T distance(const krs::vec3<T>& p) const
    {
        return krs::length(p) - T(1);
    }
};

int main()
{
    krs::glsl::emitter e;
    e.add(user_made_field{}, "mine");
}
