/*
 * export/xml_text.h -- private to export/: text into SVG, HTML, PDF and GLB
 * (marker.svg, report.html, the PDFs' cairo text, garment.glb's names;
 * pattern.svg may use it too). Names come from users (panel
 * names, garment file names), so the five XML specials are escaped and
 * bytes that are not UTF-8 (a Latin-1 name) become '?': the files declare
 * UTF-8, and cairo (pattern.pdf) refuses anything else.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_XML_TEXT_H
#define PZ_EXPORT_XML_TEXT_H

#include <stdio.h>
#include <string.h>

/* Length of the valid UTF-8 sequence at s (1-4), or 0 when s does not start one (overlong forms pass). */
static inline int pz_utf8_sequence(const unsigned char *s)
{
    int length = s[0] < 0x80 ? 1 : (s[0] & 0xe0) == 0xc0 ? 2 : (s[0] & 0xf0) == 0xe0 ? 3 : (s[0] & 0xf8) == 0xf0 ? 4 : 0;
    for (int i = 1; i < length; ++i)
        if ((s[i] & 0xc0) != 0x80)
            return 0;
    return length;
}

/* `text` with every byte that is not part of valid UTF-8 replaced by '?', into out (truncated to size). */
static inline const char *pz_utf8_clean(const char *text, char *out, size_t size)
{
    size_t used = 0;
    for (const unsigned char *s = (const unsigned char *)text; *s && used + 5 < size;) {
        int length = pz_utf8_sequence(s);
        if (length == 0) {
            out[used++] = '?', ++s;
            continue;
        }
        memcpy(out + used, s, (size_t)length);
        used += (size_t)length, s += length;
    }
    out[used] = '\0';
    return out;
}

/* Writes `text` with & < > " ' escaped and non-UTF-8 bytes as '?', for element content and attributes. */
static inline void pz_xml_put_text(FILE *file, const char *text)
{
    for (const unsigned char *s = (const unsigned char *)text; *s;) {
        int length = pz_utf8_sequence(s);
        switch (length ? *s : '?') {
        case '&': fputs("&amp;", file); break;
        case '<': fputs("&lt;", file); break;
        case '>': fputs("&gt;", file); break;
        case '"': fputs("&quot;", file); break;
        case '\'': fputs("&apos;", file); break;
        default: fwrite(length ? (const void *)s : "?", 1, length ? (size_t)length : 1, file);
        }
        s += length ? length : 1;
    }
}

#endif /* PZ_EXPORT_XML_TEXT_H */
