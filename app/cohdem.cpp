// cohdem command-line entry point (being built; see README).
#include <cstdio>
int main() { std::puts("cohdem"); return 0; }
