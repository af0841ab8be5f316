// (placeholder translation unit; file endpoints arrive with `rvc monitor`)
