// The entry point of the layer checks (src/CMakeLists.txt): each check links one layer's objects,
// all of them, with the layers it declares. It is never run; that it links is the check.
int main() { return 0; }
