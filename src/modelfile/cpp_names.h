// Spelling model-file names and values as C++ for the generated headers:
// identifiers that cannot collide with keywords, standard macros or the
// generator's own variables, struct names, string and double literals.
//
// Usage:
//   LocalName("theta") -> "v_theta";   MemberName("int") -> "v_int"
//   CamelCase("angle-rate") -> "AngleRate"
//   CppStringLiteral("a\"b") -> "\"a\\\"b\"";   FormatDouble(2) -> "2.0"
#ifndef ESTLAB_MODELFILE_CPP_NAMES_H_
#define ESTLAB_MODELFILE_CPP_NAMES_H_

#include <string>
#include <string_view>

namespace estlab::modelfile {

bool IsCppKeyword(std::string_view name);

// Names of standard or library macros (NULL, EOF, NAN, M_PI, EIGEN_..., ...)
// and other spellings a C++ header cannot safely use as a variable.
bool LooksLikeMacro(std::string_view name);

// Every user name (state, parameter, let, input) is spelled in the generated
// C++ behind this prefix: no keyword, macro of the headers the model is
// compiled with (a test lists them with `g++ -dM -E`) or name of the
// generator's own (T, P, S, x, u, p, dt, Vec, Params, ...) begins with it,
// so no user name can collide with one, whatever its spelling.
inline constexpr const char* kValuePrefix = "v_";

// A user identifier as a local variable of a generated function: "v_" + name.
std::string LocalName(const std::string& name);

// A parameter as a member of the generated Params struct: "v_" + name.
std::string MemberName(const std::string& name);

// "angle-rate" -> "AngleRate", "x_theta" -> "XTheta"; "" for no letters.
std::string CamelCase(std::string_view name);

// "PendulumFile" -> "PENDULUM_FILE".
std::string UpperSnakeCase(std::string_view camel);

// A C++ string literal with quotes; non-printable and non-ASCII bytes as
// three-digit octal escapes.
std::string CppStringLiteral(std::string_view text);

// Printable ASCII for a // comment: other bytes and '\' become '?'.
std::string CommentText(std::string_view text);

// The shortest decimal that reads back as exactly v (up to %.17g), always
// spelled as a double literal ("2.0", "0.001", "1e+300"). v must be finite.
std::string FormatDouble(double v);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_CPP_NAMES_H_
