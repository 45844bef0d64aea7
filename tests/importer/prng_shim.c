/* Stands in for bcryptprimitives.dll under Wine 8, which lacks it: Rust's std imports its
 * ProcessPrng on Windows. Placed beside the test importer only; Windows has the real one.
 * Built with mingw-w64: x86_64-w64-mingw32-gcc -shared -o bcryptprimitives.dll prng_shim.c */
#include <windows.h>
BOOLEAN NTAPI SystemFunction036(PVOID buffer, ULONG length); /* RtlGenRandom */

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
  while (length > 0) {
    ULONG n = length > 0x40000000 ? 0x40000000 : (ULONG)length;
    if (!SystemFunction036(data, n)) return FALSE;
    data += n;
    length -= n;
  }
  return TRUE;
}
