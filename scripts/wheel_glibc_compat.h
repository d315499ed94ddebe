/* Included first in every C++ file of the extension's wheels (scripts/build_addon.py, wheel).
 *
 * glibc 2.43 gave some float functions of libm new symbol versions (GLIBC_2.43), and a module
 * linked against it asks for them: the cp314 wheel, built in a Debian sid root, would then not
 * load in a Blender on any older glibc (Fedora 43's is 2.42). libm keeps the old versions, so
 * bind these to them: the wheels ask for no glibc newer than 2.34 (MAX_GLIBC in
 * tests/python/test_addon_install.py, which names any new symbol that needs adding here). On
 * x86-64 the old version is the first, GLIBC_2.2.5; with an older glibc it is the default one.
 */
#if defined(__x86_64__) && defined(__linux__)
__asm__(".symver sqrtf, sqrtf@GLIBC_2.2.5");
__asm__(".symver atan2f, atan2f@GLIBC_2.2.5");
__asm__(".symver acosf, acosf@GLIBC_2.2.5");
#endif
