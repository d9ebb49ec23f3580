# Writes the text of INPUT into OUTPUT as the C++ string phantasm::detail::tissue_table_csv.
file(READ ${INPUT} _text)
file(WRITE ${OUTPUT}
     "// Generated from core/data/tissues.csv; do not edit.\n"
     "namespace phantasm::detail {\n"
     "extern const char* const tissue_table_csv;\n"
     "const char* const tissue_table_csv = R\"phantasm_csv(${_text})phantasm_csv\";\n"
     "} // namespace phantasm::detail\n")
