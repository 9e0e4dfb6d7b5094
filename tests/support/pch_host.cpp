// The program that compiles the tests' shared precompiled header (GoogleTest,
// tests/CMakeLists.txt): an executable, so that the header is built with the
// same position-independence (-fPIE) as the test programs that reuse it.
int main() { return 0; }
